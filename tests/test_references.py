"""Independent references for what the rest of the suite checks only against the project's own
derivations: the Mackey–Glass series against scipy's high-order integrator by the method of
steps; subtractive clustering and fuzzy c-means against worked examples whose answers follow
from their symmetry and against Bezdek's update written out here; modified DH against
Pinocchio built from a URDF written here, link by link, from the convention's definition."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nfarm.learning import jang
from nfarm.learning.anfis import ANFIS
from nfarm.learning.fuzzy import subtractive_clustering
from nfarm.model.kinematics import fk, fk_all, jacobian
from nfarm.model.robot import robot_from_dict

# -- Mackey–Glass ------------------------------------------------------------------------------

A, B, TAU, X0 = 0.2, 0.1, 17.0, 1.2          # Jang's series: a, b, τ, x(0); x = 0 before t = 0


def mackey_glass_by_steps(t_end: float, *, rtol: float = 1e-12) -> np.ndarray:
    """``x(t)`` at t = 0, 1, …, t_end by the method of steps: on each interval [kτ, (k+1)τ] the
    delayed value is known (the previous interval's dense output, 0 before t = 0), so the delay
    equation is an ordinary one, integrated by scipy's DOP853 (8th order) to ``rtol``. The
    intervals end where the delayed term is not smooth (the jump of the history at t = τ and
    its echoes at multiples of τ), so the integrator never steps across one."""
    times = np.arange(int(t_end) + 1, dtype=float)
    values = np.empty(len(times))
    history = [lambda t: 0.0]
    start, x = 0.0, X0
    while start < t_end:
        end = min(start + TAU, t_end)
        delayed = history[-1]

        def rate(t, y, delayed=delayed):
            d = delayed(t - TAU)
            return [A * d / (1 + d ** 10) - B * y[0]]

        solution = solve_ivp(rate, (start, end), [x], method="DOP853", rtol=rtol, atol=1e-14,
                             dense_output=True)
        inside = (times >= start) & (times <= end)
        values[inside] = solution.sol(times[inside])[0]
        history.append(lambda t, dense=solution.sol, lo=start, before=delayed:
                       float(dense(t)[0]) if t >= lo else before(t))
        start, x = end, solution.y[0, -1]
    return values


@pytest.fixture(scope="module")
def exact_two_delays():
    return mackey_glass_by_steps(2 * TAU)


def test_the_reference_integration_is_converged(exact_two_delays):
    """The reference at 100 times looser tolerance moves by less than 1e-9: its own error is
    far below every difference the tests below measure (1e-7 and up)."""
    assert np.abs(mackey_glass_by_steps(2 * TAU, rtol=1e-10) - exact_two_delays).max() < 1e-9


@pytest.mark.parametrize("h", [0.1, 0.05])
def test_mackey_glass_before_the_delay_acts_is_the_exact_decay(h):
    """For t < τ the delayed value is the history, 0, so ``x = x0 e^{−bt}`` exactly; RK4's
    global error is then at most t · x0 · (bh)⁵/120 / h (its local error on a linear decay)."""
    t = np.arange(int(TAU))
    x = jang.mackey_glass(t_end=TAU, h=h)[:len(t)]
    bound = t * X0 * (B * h) ** 5 / 120 / h
    assert (np.abs(x - X0 * np.exp(-B * t)) <= bound + 1e-15).all()


def test_mackey_glass_is_second_order_accurate(exact_two_delays):
    """What the docstring promises (only the half-step stages interpolate; the step that ends at
    t = τ sees 0 up to its end): over the first two delays (before an error feeds back through
    the delay) second-order convergence to the high-resolution solution — linear interpolation
    of the delayed value at the half steps leaves O(h²), so halving h divides the error by 4
    (3.5–4.5 allowed). Before issue 40's fix the step ending at τ took x(0) at its last stage,
    an O(h) error of h/6 · a x0/(1 + x0¹⁰) = 5.6e-4 at h = 0.1."""
    errors = [np.abs(jang.mackey_glass(t_end=2 * TAU, h=h) - exact_two_delays).max() for h in (0.1, 0.05)]
    assert 3.5 < errors[0] / errors[1] < 4.5, errors


# -- subtractive clustering --------------------------------------------------------------------


def three_rings() -> tuple[np.ndarray, np.ndarray]:
    """Three groups far apart (distance 1 or more in a unit-sized box): a point with 8, 6 and 4
    others on a circle of radius 0.03 around it, in the plane of the first two coordinates.
    A group's centre has the highest potential in it (it minimises the sum of squared distances
    to the others, and the potentials are nearly ``Σ(1 − α d²)`` at these distances), the
    larger group the higher potential; after a centre is taken the rest of its group is left with
    potential below 0 (its points lie well inside the subtracted bump of radius 1.25 rₐ)."""
    centres = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
    points = []
    for centre, k in zip(centres, (8, 6, 4)):
        angles = 2 * np.pi * np.arange(k) / k
        ring = centre + 0.03 * np.column_stack([np.cos(angles), np.sin(angles), np.zeros(k)])
        points += [centre, *ring]
    return np.array(points), centres


def test_subtractive_clustering_finds_the_centres_of_the_worked_example():
    """Chiu (1994) on :func:`three_rings`: exactly the three group centres, largest group first."""
    data, centres = three_rings()
    found = subtractive_clustering(data, 0.5)
    np.testing.assert_allclose(found, centres, atol=1e-12)


def test_anfis_rules_from_subtractive_clustering_are_the_worked_example_s():
    """Through ANFIS (inputs the first two coordinates, output the third): one rule per centre,
    Gaussians at the centres with Chiu's width ``σ = rₐ (max − min) / √8`` per input (MATLAB's
    ``subclust``, which genfis2 uses)."""
    data, centres = three_rings()
    radius = 0.5
    model = ANFIS(partition="subtractive", mf="gauss", radius=radius, epochs=1).fit(data[:, :2], data[:, 2])
    assert len(model.rules_) == 3
    span = np.ptp(data[:, :2], axis=0)
    for i, params in enumerate(model.mfs_initial_):
        np.testing.assert_allclose(params[:, 1], centres[:, i], atol=1e-12)
        np.testing.assert_allclose(params[:, 0], radius * span[i] / math.sqrt(8), rtol=1e-12)


# -- fuzzy c-means ------------------------------------------------------------------------------

#: Bezdek's (1981) butterfly: two wings of seven points joined by one, symmetric about x = 3
#: and y = 2.
BUTTERFLY = np.array([[0, 0], [0, 2], [0, 4], [1, 1], [1, 2], [1, 3], [2, 2], [3, 2], [4, 2],
                      [5, 1], [5, 2], [5, 3], [6, 0], [6, 2], [6, 4]], dtype=float)


def bezdek(data: np.ndarray, centres: np.ndarray, m: float = 2.0, steps: int = 2000):
    """Fuzzy c-means written out from Bezdek (1981): memberships
    ``u_ij = 1 / Σ_k (‖x_j − v_i‖ / ‖x_j − v_k‖)^(2/(m−1))``, centres
    ``v_i = Σ_j u_ij^m x_j / Σ_j u_ij^m``, alternated ``steps`` times from ``centres``."""
    for _ in range(steps):
        d = np.array([[np.linalg.norm(x - v) for x in data] for v in centres])        # (c, N)
        u = np.array([[1 / sum((d[i, j] / d[k, j]) ** (2 / (m - 1)) for k in range(len(centres)))
                       for j in range(len(data))] for i in range(len(centres))])
        centres = (u ** m) @ data / (u ** m).sum(axis=1, keepdims=True)
    return centres, u


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fuzzy_c_means_of_anfis_is_bezdek_s_on_the_butterfly(seed):
    """Two clusters of the butterfly (inputs x, output y): the centres are symmetric about the
    body, (3 ∓ δ, 2), with δ that of Bezdek's iteration written out here, and each rule's
    Gaussian width is the fuzzy spread ``σ² = Σ u² (x − v)² / Σ u²`` of its memberships.
    Bezdek's iteration gives δ = 2.14523 (centres 0.85477 and 5.14523). Tolerance: the
    clustering stops when the memberships move by less than 1e-10, and the iteration contracts,
    so the centres are within about that of the fixed point (1e-8 allowed; measured 5e-11, the
    widths 1e-11 relative)."""
    model = ANFIS(partition="fcm", n_rules=2, mf="gauss", epochs=1, fcm_tolerance=1e-10,
                  random_state=seed).fit(BUTTERFLY[:, :1], BUTTERFLY[:, 1])
    params = model.mfs_initial_[0]
    order = np.argsort(params[:, 1])
    centres, u = bezdek(BUTTERFLY, np.array([[1.5, 1.7], [4.5, 2.5]]))     # no sample on a centre
    np.testing.assert_allclose(centres[:, 1], 2.0, atol=1e-12)                   # symmetric in y
    np.testing.assert_allclose(centres[:, 0].sum(), 6.0, atol=1e-12)             # and about x = 3
    assert 0.5 < 3 - centres[0, 0] < 3                                           # two wings, not one
    np.testing.assert_allclose(params[order, 1], centres[:, 0], atol=1e-8)
    spread = ((u ** 2) * (BUTTERFLY[:, 0][None] - centres[:, :1]) ** 2).sum(axis=1) / (u ** 2).sum(axis=1)
    np.testing.assert_allclose(params[order, 0], np.sqrt(spread), rtol=1e-8)


# -- modified DH against Pinocchio ------------------------------------------------------------


def _rpy(R: np.ndarray) -> tuple[float, float, float]:
    """URDF's roll, pitch, yaw of ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (away from pitch = ±90°)."""
    return (math.atan2(R[2, 1], R[2, 2]), math.asin(-R[2, 0]), math.atan2(R[1, 0], R[0, 0]))


def _rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                              math.cos(yaw), math.sin(yaw))
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def modified_dh_urdf(a, alpha, d, offset, base_rpy, base_xyz, tool_rpy, tool_xyz) -> str:
    """A URDF of the modified-DH chain (Craig 1989): link i is placed in link i−1 by
    ``Rx(α_i) Tx(a_i)`` (a fixed joint: URDF's origin is translation then rotation, and
    Tx(a) Rx(α) = Rx(α) Tx(a)), then ``Tz(d_i) Rz(offset_i) Rz(q_i)`` (the revolute joint about
    its z axis, Rz and Tz commuting). DH frame i is link ``dh{i}``'s frame."""
    f = lambda *v: " ".join(repr(float(x)) for x in v)  # noqa: E731
    parts = ['<robot name="modified">', '<link name="world"/>', '<link name="dh0"/>',
             f'<joint name="base_fixed" type="fixed"><parent link="world"/><child link="dh0"/>'
             f'<origin xyz="{f(*base_xyz)}" rpy="{f(*base_rpy)}"/></joint>']
    for i in range(len(a)):
        parts += [f'<link name="twist{i + 1}"/>',
                  f'<joint name="twist{i + 1}_fixed" type="fixed"><parent link="dh{i}"/><child link="twist{i + 1}"/>'
                  f'<origin xyz="{f(a[i], 0.0, 0.0)}" rpy="{f(alpha[i], 0.0, 0.0)}"/></joint>',
                  f'<link name="dh{i + 1}"><inertial><mass value="1"/>'
                  f'<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>',
                  f'<joint name="q{i + 1}" type="revolute"><parent link="twist{i + 1}"/><child link="dh{i + 1}"/>'
                  f'<origin xyz="{f(0.0, 0.0, d[i])}" rpy="{f(0.0, 0.0, offset[i])}"/><axis xyz="0 0 1"/>'
                  f'<limit lower="-7" upper="7" effort="1" velocity="1"/></joint>']
    parts += ['<link name="tool"/>',
              f'<joint name="tool_fixed" type="fixed"><parent link="dh{len(a)}"/><child link="tool"/>'
              f'<origin xyz="{f(*tool_xyz)}" rpy="{f(*tool_rpy)}"/></joint>', "</robot>"]
    return "\n".join(parts)


@pytest.mark.parametrize("seed", range(6))
def test_modified_dh_matches_pinocchio_from_a_urdf_written_for_it(seed):
    """Random modified-DH chains of 1–7 joints (right angles among the twists), their URDF
    written above from the convention's definition, not by nfarm's converter: every DH frame,
    the tool pose and the tool Jacobian agree with Pinocchio's to 1e-12 (rounding of products of
    a few unit-sized transforms)."""
    import pinocchio as pin

    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 8))
    a, d = rng.uniform(-0.5, 0.5, n), rng.uniform(-0.5, 0.5, n)
    alpha = np.where(rng.random(n) < 0.4, rng.choice([0.0, np.pi / 2, -np.pi / 2, np.pi], n),
                     rng.uniform(-np.pi, np.pi, n))
    offset = rng.uniform(-np.pi, np.pi, n)
    base_rpy, tool_rpy = rng.uniform(-1.2, 1.2, 3), rng.uniform(-1.2, 1.2, 3)
    base_xyz, tool_xyz = rng.uniform(-0.3, 0.3, 3), rng.uniform(-0.2, 0.2, 3)
    base, tool = np.eye(4), np.eye(4)
    base[:3, :3], base[:3, 3] = _rotation(*base_rpy), base_xyz
    tool[:3, :3], tool[:3, 3] = _rotation(*tool_rpy), tool_xyz
    np.testing.assert_allclose(_rpy(base[:3, :3]), base_rpy, atol=1e-12)        # the helpers agree
    robot = robot_from_dict({
        "name": "modified", "convention": "modified", "gravity": [0.0, 0.0, -9.81],
        "base": base.tolist(), "tool": tool.tolist(),
        "joints": [{"a": float(a[i]), "alpha": float(alpha[i]), "d": float(d[i]), "offset": float(offset[i]),
                    "qlim": [-3.0, 3.0], "mass": 1.0, "com": [0.0, 0.0, 0.0],
                    "inertia": [0.01, 0.01, 0.01, 0.0, 0.0, 0.0]} for i in range(n)]}, source="<test>")
    model = pin.buildModelFromXML(modified_dh_urdf(a, alpha, d, offset, base_rpy, base_xyz, tool_rpy, tool_xyz))
    data = model.createData()
    frames = [model.getFrameId(f"dh{i}") for i in range(n + 1)]
    tool_id = model.getFrameId("tool")
    assert model.nq == n
    for q in rng.uniform(-np.pi, np.pi, (10, n)):
        pin.framesForwardKinematics(model, data, q)
        np.testing.assert_allclose(fk_all(robot, q), [data.oMf[f].homogeneous for f in frames], rtol=0, atol=1e-12)
        np.testing.assert_allclose(fk(robot, q), data.oMf[tool_id].homogeneous, rtol=0, atol=1e-12)
        pin.computeJointJacobians(model, data, q)
        J = pin.getFrameJacobian(model, data, tool_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        np.testing.assert_allclose(jacobian(robot, q), J.reshape(6, n), rtol=0, atol=1e-12)
