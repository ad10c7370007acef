"""A shifted test population (issue 66): targets that no choice of a model met, declared in the
study file before they are drawn (its ``shifted`` section, :class:`nfarm.study.study_files.ShiftedSection`)
and read once, by chapter 7, with the frozen models, so that the verdict is seen beside one on a
population the study's choices were not tuned to.

The test split is drawn from the same generator as the training and validation data, only from
another seed: a redraw does not undo choices made on that population. The shifted IK population
lies **just beyond the region**: configurations with every joint within ``ik_band`` of its range's
width beyond the ends of the region's box (and within the joint's limits), at least one joint
outside the box, the region's task-space filters kept (:func:`beyond_box`) — poses no model was
trained, tuned or chosen on, each a small step past the data, where every learner extrapolates.
It is drawn by independent uniform draws from its own seed, in batches, until ``ik_samples`` are
kept.

The shifted ID population (:func:`shifted_id`, where the section declares ``id_trajectories``) is
**faster than any trajectory the models met**: the study's generator with its paths run ``id_speed``
times as fast — the velocity bounds times ``id_speed``, the acceleration bounds times its square,
the segments' nominal times divided by it — so that the states lie beyond the training data's
speeds and accelerations, where the rigid body's velocity-product and inertial torques and the
drives' friction all grow. Its torques are the model's (the rigid-body task) and, for a study with
a measured arm, the built arm's as its sensors read them, on the states its encoders give
(:func:`nfarm.study.datasets.measured_readings`), each from streams of the section's ``seed``.

Both are made in memory when a chapter asks for them (a few thousand forward kinematics; tens of
trajectories), and are not data sets of :mod:`nfarm.study.datasets`: the data sets' hash leaves the
``shifted`` section out, so declaring it retrains nothing.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..infra.arguments import check_number
from ..model.dynamics import rnea
from ..model.kinematics import fk
from .datasets import measured_readings
from .id_trajectories import measured_states, random_trajectories
from .regions import STREAMS, IKRegion
from .study_files import Study, redrawn

__all__ = ["boundary_distance", "beyond_box", "shifted_ik", "shifted_id", "shifted_readings", "faster", "describe", "describe_id"]

#: The shifted ID population's stream below the section's seed (the IK one draws from the seed itself).
_ID_STREAM = 1


def boundary_distance(region: IKRegion, q: np.ndarray) -> np.ndarray:
    """``(...)``: how far configurations ``q (..., n)`` [rad] lie inside the region's joint box, as the
    least over the joints of the signed distance to the nearer end of the joint's range, in shares
    of that range's width: 0 on the box's boundary, 0.5 at the centre of every joint's range,
    negative outside the box.

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.model.robot import load_robot
        >>> robot = load_robot(PARAMS / "robots" / "intelbot5.yaml")
        >>> region = IKRegion(robot, np.array([[-1.0, 1.0]] * 5))
        >>> boundary_distance(region, np.array([[0.0, 0.0, 0.0, 0.0, 0.9], [0.0] * 5, [1.1] + [0.0] * 4])).round(3).tolist()
        [0.05, 0.5, -0.05]
    """
    lo, hi = region.box[:, 0], region.box[:, 1]
    share = np.minimum(q - lo, hi - q) / (hi - lo)
    return share.min(axis=-1)


def beyond_box(region: IKRegion, n: int, band: float, seed: int, *, batch: int = 20_000,
               max_draws: int = 20_000_000) -> np.ndarray:
    """``n`` configurations ``(n, dof)`` [rad] just beyond the region's joint box: every joint within
    ``band`` of its range's width beyond the box's ends (clipped to the joint's limits), at least one
    outside the box (:func:`boundary_distance` below 0), and the region's task-space filters met — by
    independent uniform draws from ``seed``.

    Raises:
        ValueError: a ``band`` outside ``(0, 0.5]``; a box at every joint's limits (nothing lies
            beyond it); too few draws kept within ``max_draws``.
    """
    check_number("band", band, 0, 0.5, open_lo=True, open_hi=False, finite=False, numpy=False,
                 message=f"band must be in (0, 0.5], got {band!r}")
    lo, hi = region.box[:, 0], region.box[:, 1]
    limits = region.robot.qlim
    wide = np.column_stack([np.maximum(lo - band * (hi - lo), limits[:, 0]), np.minimum(hi + band * (hi - lo), limits[:, 1])])
    if np.array_equal(wide, region.box):
        raise ValueError("the region's box lies at every joint's limits: no configuration lies beyond it")
    outer = dataclasses.replace(region, box=wide)
    rng = np.random.default_rng(seed)
    kept, drawn = [], 0
    while sum(len(k) for k in kept) < n:
        if drawn >= max_draws:
            raise ValueError(f"beyond the region's box by {band:g} of its ranges, {sum(len(k) for k in kept):,} of "
                             f"{drawn:,} configurations drawn were kept, fewer than the {n:,} asked: widen ik_band "
                             f"or lower ik_samples")
        q = outer.sample(batch, rng, method="uniform")
        drawn += batch
        kept.append(q[boundary_distance(region, q) < 0])
    return np.concatenate(kept)[:n]


def shifted_ik(study: Study) -> dict[str, np.ndarray]:
    """The study's shifted IK targets: ``q (N, n)`` [rad] just beyond the region (:func:`beyond_box`,
    the study file's ``shifted`` section) and ``T = fk(q) (N, 4, 4)``.

    Raises:
        ValueError: a study that declares no shifted population.
    """
    if study.shifted is None:
        raise ValueError(f"{study.source}: shifted: the study declares no shifted test population")
    s = study.shifted
    q = beyond_box(study.ik_region, s.ik_samples, s.ik_band, s.seed)
    return {"q": q, "T": fk(study.robot, q)}


def faster(settings, speed: float):
    """The ID generator's ``settings`` (:class:`nfarm.study.id_trajectories.IDSettings`) with its
    paths run ``speed`` times as fast: velocity bounds × ``speed``, acceleration bounds ×
    ``speed``², the segments' nominal times ÷ ``speed`` (a path's timing compressed by ``speed``).

    Example:
        >>> from nfarm.infra.paths import PARAMS
        >>> from nfarm.study.study_files import load_study
        >>> s = load_study(PARAMS / "studies" / "intelbot5.yaml").id
        >>> f = faster(s, 2.0)
        >>> bool(np.allclose(f.max_velocity, 2 * s.max_velocity)), f.segment_time == (0.3, 0.9)
        (True, True)
    """
    check_number("speed", speed, 0, None, open_lo=True, numpy=False, message=f"speed must be a positive number, got {speed!r}")
    return dataclasses.replace(settings, max_velocity=speed * settings.max_velocity,
                               max_acceleration=speed ** 2 * settings.max_acceleration,
                               segment_time=tuple(t / speed for t in settings.segment_time))


def shifted_id(study: Study) -> dict[str, np.ndarray]:
    """The study's shifted ID trajectories (module docstring): ``q, qd, qdd (N, n)`` [rad, rad/s,
    rad/s²], ``trajectory (N,)``, ``tau (N, n)`` [N·m] the model's rigid-body torques and, for a
    measured arm, ``tau_measured`` (and ``tau_payload`` where its built arm declares a payload)
    with the states its encoders give (``q_measured``, ``qd_measured``, ``qdd_measured``).

    Raises:
        ValueError: a study that declares no shifted ID population.
    """
    s = study.shifted
    if s is None or s.id_trajectories is None:
        raise ValueError(f"{study.source}: shifted: id_trajectories: the study declares no shifted ID population")
    settings = faster(study.id, s.id_speed)
    data = random_trajectories(study.robot, settings, s.id_trajectories, np.random.SeedSequence([s.seed, _ID_STREAM]))
    data["tau"] = rnea(study.robot, data["q"], data["qd"], data["qdd"])
    if settings.measured is not None:
        data.update(measured_readings(study, data, [s.seed, _ID_STREAM, STREAMS["id_noise"]], payload=True))
        if settings.encoder_counts is not None:
            data["q_measured"], data["qd_measured"], data["qdd_measured"] = measured_states(
                data["q"], data["trajectory"], settings.dt, settings.encoder_counts, settings.filter_window)
    return data


def shifted_readings(study: Study, data, draw: int) -> dict[str, np.ndarray]:
    """What the arm built for ``draw`` (:func:`nfarm.study.datasets.built_arm` of the redrawn study)
    reads on the shifted trajectories ``data`` (:func:`shifted_id`): ``tau_measured`` and, where the
    built arm declares a payload, ``tau_payload`` — draw 0's are ``data``'s own; another draw's noise
    comes from the population's stream extended by the draw. A draw's models are judged against
    the arm they were trained on.

    Raises:
        ValueError: a study that declares no shifted ID population or no measured arm.
    """
    s = study.shifted
    if s is None or s.id_trajectories is None or study.id.measured is None:
        raise ValueError(f"{study.source}: shifted: the study declares no shifted ID population of a measured arm")
    if draw == 0:
        return {k: data[k] for k in ("tau_measured", "tau_payload") if k in data}
    return measured_readings(redrawn(study, draw), data, [s.seed, _ID_STREAM, STREAMS["id_noise"], int(draw)],
                             payload=True)


def describe_id(study: Study) -> str:
    """The shifted ID population in words, for captions and prose."""
    s = study.shifted
    if s is None or s.id_trajectories is None:
        return "no shifted ID population"
    return (f"{s.id_trajectories:,} trajectories of the study's generator run {s.id_speed:g} times as fast (speeds up to "
            f"{s.id_speed:g}×, accelerations up to {s.id_speed ** 2:g}× the training trajectories' bounds; seed {s.seed}, "
            f"declared {s.id_declared or s.declared})")


def describe(study: Study) -> str:
    """The shifted population in words, for captions and prose."""
    if study.shifted is None:
        return "no shifted population"
    s = study.shifted
    return (f"{s.ik_samples:,} targets just beyond the region (every joint within {s.ik_band:.0%} of its range's width "
            f"beyond the region's box, at least one outside it; seed {s.seed}, declared {s.declared})")
