"""Shared fixtures: the project's robots, random DH chains and their Pinocchio references."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

from nfarm.infra.paths import ROOT
from nfarm.model.robot import ParamsWarning, Robot, load_robot, robot_from_dict
from nfarm.model.rotations import quat_to_matrix

# Deterministic property tests: the same examples on every run and every machine.
settings.register_profile("nfarm", derandomize=True, deadline=None, max_examples=40,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("nfarm")

ROBOT_FILES = sorted((ROOT / "params" / "robots").glob("*.yaml"))


def load_quietly(path: Path) -> Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ParamsWarning)
        return load_robot(path)


@pytest.fixture(params=ROBOT_FILES, ids=lambda p: p.stem)
def robot(request) -> Robot:
    """Every robot shipped in params/robots/."""
    return load_quietly(request.param)


@pytest.fixture
def intelbot5() -> Robot:
    return load_robot(ROOT / "params" / "robots" / "intelbot5.yaml")


@pytest.fixture
def puma560() -> Robot:
    return load_quietly(ROOT / "params" / "robots" / "puma560.yaml")


_SPECIAL_ANGLES = [0.0, np.pi / 2, -np.pi / 2, np.pi]


def _angle():
    return st.one_of(st.sampled_from(_SPECIAL_ANGLES), st.floats(-np.pi, np.pi))


def _length():
    return st.one_of(st.just(0.0), st.floats(-0.8, 0.8))


@st.composite
def random_chains(draw, min_joints: int = 1, max_joints: int = 7) -> Robot:
    """A random revolute chain of either DH convention, with a random tool and inertias (and,
    for some standard chains, fixed transforms after some rows)."""
    n = draw(st.integers(min_joints, max_joints))
    convention = draw(st.sampled_from(["standard", "modified"]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    joints = []
    for _ in range(n):
        lo = draw(st.floats(-np.pi, 0.0, exclude_max=True))
        principal = rng.uniform(0.05, 0.1, 3)  # any two sum to more than the third: physical
        R = quat_to_matrix(rng.normal(size=4))
        inertia = R @ np.diag(principal) @ R.T
        joints.append({
            "a": draw(_length()), "alpha": draw(_angle()), "d": draw(_length()),
            "offset": draw(_angle()), "qlim": [lo, draw(st.floats(0.0, np.pi, exclude_min=True))],
            "mass": float(rng.uniform(0.1, 3.0)), "com": rng.uniform(-0.3, 0.3, 3).tolist(),
            "inertia": [inertia[0, 0], inertia[1, 1], inertia[2, 2],
                        inertia[0, 1], inertia[1, 2], inertia[0, 2]],
        })
    if convention == "standard" and draw(st.booleans()):
        # Fixed transforms after some rows (a URDF's nearly parallel axes; any placement):
        # a tilt of 1e-12 to 0.1 rad about a random axis and a shift of up to 5 cm.
        for joint in joints:
            if rng.random() < 0.5:
                E = np.eye(4)
                E[:3, :3] = quat_to_matrix(np.r_[1.0, rng.normal(size=3) * 10 ** rng.uniform(-12, -1)])
                E[:3, 3] = rng.uniform(-0.05, 0.05, 3) * (rng.random() < 0.5)
                joint["fixed"] = E.tolist()
    tool = np.eye(4)
    if draw(st.booleans()):
        tool[:3, :3] = quat_to_matrix(rng.normal(size=4))
        tool[:3, 3] = rng.uniform(-0.2, 0.2, 3)
    extra = {}
    if draw(st.booleans()):          # a base that places DH frame 0 anywhere in the world
        base = np.eye(4)
        base[:3, :3] = quat_to_matrix(rng.normal(size=4))
        base[:3, 3] = rng.uniform(-0.5, 0.5, 3)
        extra["base"] = base.tolist()
    return robot_from_dict({
        "name": f"random{n}{convention[0]}", "convention": convention,
        "gravity": [0.0, 0.0, -9.81], "tool": tool.tolist(), "joints": joints, **extra,
    }, source="<random chain>")


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """`make test` keeps each chain of chapters (05 → 06 → 07 → 08) in one pytest-xdist worker
    (``--dist loadgroup``), where its data and models are made once. A pytest/xdist pair that
    ignores the groups (pytest-xdist 3.8 under pytest 9 did: every chain ran twice, a minute
    more) is refused here rather than found in the suite's time."""
    if getattr(config.option, "loadgroup", False):
        lost = [item.nodeid for item in items
                if any(item.iter_markers("xdist_group")) and "@" not in item.nodeid]
        if lost:
            raise pytest.UsageError(f"--dist loadgroup is not grouping tests ({lost[0]} has no group suffix): "
                                    f"pytest-xdist and pytest disagree; use the versions in environment.lock")


#: Tests that skip where a program is missing (Chromium and its driver): on a developer's
#: machine a skip with its one-line reason, but under CI (``CI=true``, set by the CI runner for
#: ``.ci/run``, which installs them) a failure, so that a green run has run them.
NEEDS_INSTALLED = {"test_panel_browser.py"}


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if report.skipped and os.environ.get("CI") == "true" and item.path.name in NEEDS_INSTALLED \
            and not hasattr(report, "wasxfail"):
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
        report.outcome = "failed"
        report.longrepr = f"CI=true and this test skipped ({reason}): .ci/run installs what it needs"
