"""The verdict's history is read from the repository, not typed: every split's last publication,
the development split named as such, and the working tree's verdict as "now"."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from nfarm.publishing.editions import Edition
from nfarm.publishing.history import DEVELOPMENT, verdict_history

HEAD = "arm,task,metric,unit,verdict,gap,gap_low,gap_high\n"


def _commit(root: Path, verdict: str, gap: str, test_seed: int | None, message: str) -> None:
    (root / "params" / "studies").mkdir(parents=True, exist_ok=True)
    (root / "figures" / "tables").mkdir(parents=True, exist_ok=True)
    (root / "params" / "studies" / "a.yaml").write_text(
        "name: a\nseed: 0\n" + (f"test_seed: {test_seed}\n" if test_seed is not None else ""))
    (root / "figures" / "tables" / "07_verdict.csv").write_text(
        HEAD + f"a,inverse kinematics,position p95,mm,{verdict},{gap},{float(gap) - 0.1},{float(gap) + 0.1}\n")
    subprocess.run(["git", "add", "-A"], cwd=root, check=True)
    subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", message], cwd=root, check=True)


@pytest.fixture
def repo(tmp_path):
    subprocess.run(["git", "init", "-q"], cwd=tmp_path, check=True)
    _commit(tmp_path, "ANFIS better", "-2.2", None, "development")
    _commit(tmp_path, "ANFIS better", "-2.1", 1, "split 1")
    _commit(tmp_path, "ANFIS better", "-1.5", 1, "split 1 again")        # the split's last publication counts
    _commit(tmp_path, "no difference", "0.05", 2, "split 2")
    return tmp_path


def test_every_split_read_has_its_last_published_verdict(repo):
    arm = Edition("a", "params/studies/a.yaml", "params/robots/a.yaml", True)
    rows = verdict_history([arm], root=repo)
    assert [(r.split, r.verdict, r.gap) for r in rows] == [
        (DEVELOPMENT, "ANFIS better", "-2.2 (-2.3000000000000003 to -2.1)"),
        ("1", "ANFIS better", "-1.5 (-1.6 to -1.4)"), ("2", "no difference", "0.05 (-0.05 to 0.15000000000000002)")]
    assert rows[-1].commit == "now", "the working tree's verdict stands for its split"
    assert len({r.commit for r in rows}) == 3 and all(r.unit == "mm" for r in rows)


def test_a_verdict_published_now_on_a_new_split_is_a_split_of_its_own(repo):
    arm = Edition("a", "params/studies/a.yaml", "params/robots/a.yaml", True)
    (repo / "params" / "studies" / "a.yaml").write_text("name: a\nseed: 0\ntest_seed: 3\n")
    (repo / "figures" / "tables" / "07_verdict.csv").write_text(
        HEAD + "a,inverse kinematics,position p95,mm,ANFIS better,-1.0,-1.1,-0.9\n")
    rows = verdict_history([arm], root=repo)
    assert [(r.split, r.commit == "now") for r in rows] == [(DEVELOPMENT, False), ("1", False), ("2", False),
                                                            ("3", True)]


def test_without_git_history_the_published_verdict_alone(tmp_path):
    (tmp_path / "figures" / "tables").mkdir(parents=True)
    (tmp_path / "figures" / "tables" / "07_verdict.csv").write_text(
        HEAD + "a,inverse kinematics,position p95,mm,ANFIS better,-1.0,-1.1,-0.9\n")
    arm = Edition("a", "params/studies/a.yaml", "params/robots/a.yaml", True)
    rows = verdict_history([arm], root=tmp_path)
    assert [(r.split, r.commit) for r in rows] == [(DEVELOPMENT, "now")]


def test_the_project_history_holds_every_split_of_the_study():
    """The committed history: the development split and the test_seed splits before this one."""
    from nfarm.publishing.editions import editions

    rows = verdict_history(editions())
    if not any(r.commit != "now" for r in rows):
        pytest.skip("a checkout without the repository's history")
    ik = [r for r in rows if r.arm == "intelbot5" and r.task == "inverse kinematics"]
    assert [r.split for r in ik][:6] == [DEVELOPMENT, "20261126", "20261127", "20261128", "20261129", "20261130"]
    # The IK gap kept its sign on every split until the Gaussian process joined the contest (issue 64, 2026120707):
    # from that split on another learner is the better tool
    turned = [r.split for r in ik].index("2026120707")
    assert all(r.verdict == "ANFIS better" for r in ik[:turned]), "the IK gap kept its sign before the Gaussian process"
    assert ik[turned].verdict == "rival better"
