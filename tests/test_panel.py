"""The arm panel driven headlessly: widget values set as a reader would, what it shows checked
against the library's own functions (fk, the closed form, LM, the trajectories, rnea)."""

from __future__ import annotations

import html
import re
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nfarm.publishing import panel_compute as pc
from nfarm.study.regions import ik_samples
from nfarm.study.study_files import load_study
from nfarm.model.dynamics import rnea
from nfarm.solvers.geometric_ik import in_class
from nfarm.model.kinematics import fk, fk_all
from nfarm.learning.learned import LearnedIK
from nfarm.learning.learned_id import LearnedID
from nfarm.publishing.panel import ArmPanel, Panel
from nfarm.infra.paths import PARAMS
from nfarm.model.robot import load_robot, sample_configurations
from nfarm.model.rotations import pose_error, quat_to_matrix, rpy_to_matrix

with warnings.catch_warnings():          # the Puma's published inertias are not physical
    warnings.simplefilter("ignore")
    ROBOTS = {name: load_robot(path) for name, path in pc.shipped_robots().items()}


def numbers(text: str) -> list[float]:
    """The numbers an HTML fragment shows, in order."""
    plain = re.sub(r"<[^>]+>", " ", html.unescape(text))
    return [float(x) for x in re.findall(r"[-+]?\d+\.?\d*(?:e[-+]?\d+)?", plain)]


@pytest.fixture(scope="module")
def panels(tmp_path_factory):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {name: ArmPanel(name, models_dir=tmp_path_factory.mktemp(f"no-models-{name}"),
                               recordings_dir=tmp_path_factory.mktemp("recordings"))
                for name in ROBOTS}


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """Small learned IK and ID models of intelbot5, saved where the panel looks for them."""
    study = load_study(PARAMS / "studies" / "intelbot5.yaml")
    robot = study.robot
    models = tmp_path_factory.mktemp("models")
    ik = LearnedIK(encoding="arm_plane", n_mfs=[1, 2, 2, 2, 2, 1], epochs=4,
                   joint_options=[{"n_mfs": 1}, {}, {}, {}, {"n_mfs": 1}])
    ik.fit(robot, ik_samples(study.ik_region, 1500, 1)).save(models / "ik")
    rng = np.random.default_rng(3)
    q = sample_configurations(robot, 3000, seed=4)
    qd, qdd = rng.uniform(-1, 1, q.shape), rng.uniform(-2, 2, q.shape)
    LearnedID(inputs="affine", n_mfs=1, epochs=1).fit(
        robot, {"q": q, "qd": qd, "qdd": qdd, "tau": rnea(robot, q, qd, qdd)}).save(models / "id_model_free")
    return models


# -- forward kinematics --------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_sliders_show_the_tool_pose_of_fk(panels, name):
    panel, robot = panels[name], ROBOTS[name]
    q = sample_configurations(robot, 1, seed=5)[0]
    for slider, value in zip(panel.fk.sliders, np.degrees(q)):
        slider.value = float(value)
    q = panel.fk.q                                          # as the sliders hold it (step 0.5°)
    T = fk(robot, q)
    shown = numbers(panel.fk.readout.value)
    np.testing.assert_allclose(shown[:3], T[:3, 3] * 1e3, atol=0.006)        # position [mm], 2 decimals
    R = rpy_to_matrix(np.radians(shown[3:6]))
    np.testing.assert_allclose(R, T[:3, :3], atol=2e-4)                       # roll-pitch-yaw [deg]
    np.testing.assert_allclose(quat_to_matrix(shown[6:10]), T[:3, :3], atol=2e-3)
    np.testing.assert_allclose(shown[10:19], T[:3, :3].ravel(), atol=6e-5)    # the rotation matrix
    # The drawing moved with the sliders: links through the frames' origins to the tool.
    points = np.vstack([fk_all(robot, q)[:, :3, 3], T[:3, 3]])
    np.testing.assert_allclose(np.array(panel.fk.view.links.get_data_3d()).T, points, atol=1e-12)
    assert panel.fk.message.value == ""


def test_a_stretched_arm_is_said_to_be_near_a_singularity(panels):
    panel = panels["intelbot5"]
    panel.fk.set_q(np.zeros(5))            # tool axis along the base axis: a wrist singularity
    assert "Near a singularity" in panel.fk.warning.value
    panel.fk.set_q(np.radians([10, 30, -60, -30, 10]))
    assert panel.fk.warning.value == ""


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_pose_readout_agrees_with_its_rotation_forms(seed):
    robot = ROBOTS["so101"]
    q = sample_configurations(robot, 1, seed=seed)[0]
    r = pc.pose_readout(robot, q)
    np.testing.assert_allclose(rpy_to_matrix(np.radians(r.rpy_deg)), r.T_0e[:3, :3], atol=1e-12)
    np.testing.assert_allclose(quat_to_matrix(r.quat), r.T_0e[:3, :3], atol=1e-12)
    assert r.quat[0] >= 0 and r.sigma_position_m > 0


# -- inverse kinematics --------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_every_answer_to_a_pose_of_the_arm_is_checked_at_the_tool(panels, name):
    panel, robot = panels[name], ROBOTS[name]
    panel.fk.set_q(sample_configurations(robot, 1, seed=11)[0] * 0.6)
    panel.ik.from_arm.click()
    T = panel.ik.target()                                   # the arm's pose, as the fields hold it
    np.testing.assert_allclose(T, fk(robot, panel.fk.q), atol=1e-8)
    answers = panel.ik.answers
    assert panel.ik.message.value == ""
    methods = [a.method for a in answers]
    assert sum(m.startswith("closed form") for m in methods) == (4 if in_class(robot) else 1)
    for a in answers:
        if a.q is not None:
            e = pose_error(fk(robot, a.q), T)
            assert a.pos_error_m == pytest.approx(np.linalg.norm(e[:3]), abs=1e-15)
    lm = next(a for a in answers if a.method == "Levenberg–Marquardt")
    assert lm.reaches and lm.pos_error_m < 1e-8
    if in_class(robot):
        assert any(a.reaches for a in answers if a.method.startswith("closed form"))
    else:
        assert "not for this arm" in answers[0].note
    assert "no trained model" in answers[-1].note and answers[-1].q is None
    # The table shows every answer's angles in degrees.
    for a in answers:
        if a.q is not None:
            assert f"{np.degrees(a.q[0]):.2f}" in panel.ik.answers_html.value


def test_nudging_moves_the_target_and_answers_again(panels):
    panel = panels["intelbot5"]
    panel.fk.set_q(np.radians([10, 30, -60, -30, 10]))
    panel.ik.from_arm.click()
    z = panel.ik.fields[2].value
    before = panel.ik.answers
    panel.ik.step_mm.value = 5.0
    panel.ik.nudge_buttons[2, -1].click()                  # z −
    assert panel.ik.fields[2].value == pytest.approx(z - 5.0)
    T = panel.ik.target()
    lm = next(a for a in panel.ik.answers if a.method == "Levenberg–Marquardt")
    assert lm.reaches and np.linalg.norm(fk(ROBOTS["intelbot5"], lm.q)[:3, 3] - T[:3, 3]) < 1e-8
    assert panel.ik.answers is not before


def test_a_target_outside_the_reach_is_answered_not_raised(panels):
    panel = panels["so101"]
    panel.ik.mode.value = "position and roll-pitch-yaw"
    for field, value in zip(panel.ik.fields, [2000, 0, 500, 0, 0, 0]):
        field.value = value
    panel.ik.solve_button.click()
    assert panel.ik.message.value == ""
    assert not any(a.reaches for a in panel.ik.answers)
    notes = " ".join(a.note for a in panel.ik.answers)
    assert "target outside its pose set" in notes and "did not converge" in notes


@pytest.mark.parametrize("text, says", [
    ("1 0 0 100; 0 2 0 0; 0 0 1 100", "not orthonormal"),
    ("1 0 0 100; 0 1 0 0", "3 or 4 rows"),
    ("1 0 0 a; 0 1 0 0; 0 0 1 0", "rows of four numbers"),
    ("1 0 0 0; 0 1 0 0; 0 0 1 0; 1 0 0 1", "fourth row"),
    ("0 1 0 0; 1 0 0 0; 0 0 1 0", "determinant"),
])
def test_a_typed_pose_that_is_not_a_rotation_gets_one_line(panels, text, says):
    panel = panels["intelbot5"]
    panel.ik.mode.value = "typed matrix"
    panel.ik.matrix.value = text
    panel.ik.solve_button.click()
    message = html.unescape(re.sub(r"<[^>]+>", "", panel.ik.message.value))
    assert says in message and "\n" not in message and message.startswith("typed pose")
    panel.ik.mode.value = "position and roll-pitch-yaw"


def test_trained_models_answer_beside_the_others(trained):
    panel = ArmPanel("intelbot5", models_dir=trained)
    assert panel.models.ik is not None and panel.models.id is not None
    panel.fk.set_q(np.radians([10, 30, -60, -30, 10]))
    panel.ik.from_arm.click()
    anfis = panel.ik.answers[-1]
    assert anfis.method.startswith("ANFIS") and anfis.q is not None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        np.testing.assert_array_equal(anfis.q, panel.models.ik.predict(panel.ik.target()))
    # The small model's training data do not cover this pose: the panel says so beside the answer.
    assert caught and all(str(c.message).split(":")[0] in anfis.note for c in caught)
    parts = panel.dynamics.parts
    tr = panel.trajectory.trajectory
    np.testing.assert_array_equal(parts.learned, panel.models.id.predict(tr.q, tr.qd, tr.qdd))
    assert "learned ID" in " ".join(t.get_text() for t in panel.dynamics.fig.legends[0].get_texts())


def test_a_model_of_another_robot_is_refused_in_one_line(trained):
    models = pc.trained_models(ROBOTS["so101"], trained)
    assert models.ik is None and "cannot be used" in models.ik_note and "\n" not in models.ik_note


# -- trajectory and dynamics ---------------------------------------------------------------------


@pytest.mark.parametrize("profile", ["cubic", "quintic"])
@pytest.mark.parametrize("name", ["intelbot5", "puma560"])
def test_an_answer_sent_on_ends_the_trajectory(panels, name, profile):
    panel, robot = panels[name], ROBOTS[name]
    page = panel.trajectory
    panel.fk.set_q(sample_configurations(robot, 1, seed=21)[0] * 0.5)
    page.buttons["initial ← arm"].click()
    q_start = panel.fk.q
    panel.fk.set_q(sample_configurations(robot, 1, seed=22)[0] * 0.5)
    panel.ik.from_arm.click()
    for box, value in zip(page.v0, np.linspace(-10, 10, robot.n)):
        box.value = float(value)
    page.profile.value = profile
    panel.ik.send_button.click()
    assert panel.tabs.selected_index == panel.pages.index(page)
    answer = panel.ik.answers[panel.ik.choice.value].q
    tr = page.trajectory
    np.testing.assert_allclose(tr.t[[0, 1, -1]], [0, 0.2, 6], atol=1e-12)         # the seed's 0, 0.2, 6 s
    np.testing.assert_allclose(tr.q[0], q_start, atol=1e-9)
    np.testing.assert_allclose(tr.q[-1], np.radians(np.round(np.degrees(answer), 6)), atol=1e-9)
    np.testing.assert_allclose(np.degrees(tr.qd[0]), np.linspace(-10, 10, robot.n), atol=1e-9)
    np.testing.assert_allclose(tr.qd[-1], 0, atol=1e-9)
    # The plots show the trajectory in degrees; the torques are rnea's, split into parts.
    np.testing.assert_allclose(page.axes[0].lines[0].get_ydata(), np.degrees(tr.q[:, 0]))
    parts = panel.dynamics.parts
    np.testing.assert_allclose(parts.total, rnea(robot, tr.q, tr.qd, tr.qdd), atol=1e-12)
    np.testing.assert_allclose(parts.inertial + parts.coriolis + parts.gravity, parts.total, atol=1e-10)
    assert page.message.value == "" and panel.dynamics.message.value == ""


def test_the_animation_follows_the_trajectory(panels):
    panel, robot = panels["intelbot5"], ROBOTS["intelbot5"]
    page = panel.trajectory
    page.compute()
    k = len(page.trajectory.t) // 2
    page.frame.value = k
    np.testing.assert_allclose(np.array(page.view.links.get_data_3d())[:, -1], fk(robot, page.trajectory.q[k])[:3, 3])
    assert np.array(page.view.travelled.get_data_3d()).shape == (3, k + 1)
    assert page.frame.max == page.play.max == len(page.trajectory.t) - 1


@pytest.mark.parametrize("field, value, says", [
    ("tf", -1.0, "must be after the start time"),
    ("dt", 10.0, "at most the duration"),
    ("dt", 0.0, "must be > 0"),
    ("dt", 1e-6, "the panel draws at most"),
])
def test_bad_times_get_one_line_and_clear_the_last_trajectory(panels, field, value, says):
    panel = panels["so101"]
    page = panel.trajectory
    page.t0.value, page.dt.value, page.tf.value = 0.0, 0.2, 6.0
    page.compute()
    assert page.trajectory is not None and panel.dynamics.parts is not None
    getattr(page, field).value = value
    page.buttons["compute"].click()
    message = html.unescape(re.sub(r"<[^>]+>", "", page.message.value))
    assert says in message and "\n" not in message
    # Nothing of the last trajectory stays on the page: no plot, no torques to save.
    assert page.trajectory is None and panel.dynamics.parts is None
    assert not any(ax.lines for ax in page.axes) and not any(ax.lines for ax in panel.dynamics.axes)
    page.t0.value, page.dt.value, page.tf.value = 0.0, 0.2, 6.0


def test_leaving_the_limits_is_said(panels):
    page = panels["intelbot5"].trajectory
    robot = ROBOTS["intelbot5"]
    page._set(page.q0, np.zeros(robot.n))
    page._set(page.qf, robot.qlim[:, 1])
    page.v0[1].value = 200.0                    # overshoots the upper limit of joint 2
    page.compute()
    assert robot.joint_names[1] in page.notes.value and "leaves its limits" in page.notes.value
    page.v0[1].value = 0.0


def rrd_rows(path) -> dict[str, int]:
    """Rows per entity of a rerun recording, as rerun's own reader lists its chunks (``rerun rrd print``)."""
    import subprocess
    import sys
    from pathlib import Path

    rerun = Path(sys.executable).with_name("rerun")
    verify = subprocess.run([str(rerun), "rrd", "verify", str(path)], capture_output=True, text=True, timeout=120)
    assert verify.returncode == 0, verify.stderr
    listing = subprocess.run([str(rerun), "rrd", "print", str(path)], capture_output=True, text=True, timeout=120)
    rows: dict[str, int] = {}
    for count, entity in re.findall(r"with (\d+) rows \([^)]*\) - (/\S+) - data columns", listing.stdout):
        rows[entity] = rows.get(entity, 0) + int(count)
    return rows


def test_the_recording_is_written(panels):
    """The saved recording holds, for every joint, its angle, velocity and transform at every sample of the
    trajectory the page computed, and the tool's path: read back by rerun's own reader, not sized."""
    panel = panels["intelbot5"]
    panel.trajectory.compute()
    panel.trajectory.save_button.click()
    path = panel.recordings_dir / "intelbot5-panel-trajectory.rrd"
    assert "saved" in panel.trajectory.message.value
    samples, robot = len(panel.trajectory.trajectory.t), ROBOTS["intelbot5"]
    rows = rrd_rows(path)
    expected = {f"/{kind}/{joint}": samples for kind in ("q_deg", "qd_deg_s", "transforms") for joint in robot.joint_names}
    assert {k: rows.get(k) for k in expected} == expected
    assert rows.get("/tool_path") == samples


def test_drive_limits_are_drawn_where_the_robot_gives_them(panels):
    panel, robot = panels["so101"], ROBOTS["so101"]
    assert np.isfinite(robot.effort).all()
    panel.trajectory.compute()
    limits = [line for line in panel.dynamics.axes[0].lines if line.get_linestyle() == ":"]
    assert sorted(line.get_ydata()[0] for line in limits) == [-robot.effort[0], robot.effort[0]]
    assert "not given" in panels["intelbot5"].dynamics.peaks.value


def test_the_robot_chooser_builds_the_chosen_arm(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        panel = Panel("intelbot5", models_dir=tmp_path)
        panel.chooser.value = "puma560"
    assert panel.arm.robot.name == ROBOTS["puma560"].name and len(panel.arm.fk.sliders) == 6
    assert "not a physical rigid body" in panel.arm.widget.children[0].value   # the file's warnings, shown
    with pytest.raises(ValueError, match="robot: one of"):
        Panel("nosuch")


def test_the_panel_notebook_runs_and_shows_the_panel():
    """notebooks/arm_panel.ipynb as JupyterLab or Voilà runs it: no error, one widget shown, and
    pyplot's backend left as the kernel set it (ipympl is imported without its side effect)."""
    import nbformat
    from nbclient import NotebookClient

    from nfarm.infra.paths import NOTEBOOKS

    nb = nbformat.read(NOTEBOOKS / "arm_panel.ipynb", as_version=4)
    nb.cells.append(nbformat.v4.new_code_cell("import matplotlib; print(matplotlib.get_backend())"))
    NotebookClient(nb, kernel_name="nfarm", timeout=300, resources={"metadata": {"path": str(NOTEBOOKS)}}).execute()
    outputs = [o for cell in nb.cells if cell.cell_type == "code" for o in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error" or o.get("name") == "stderr"]
    views = [o for o in outputs if "application/vnd.jupyter.widget-view+json" in o.get("data", {})]
    assert len(views) == 1
    assert "ipympl" not in outputs[-1]["text"]


def test_jupyterlab_asks_nothing_of_the_internet():
    """make setup installs the project's JupyterLab settings into the venv: no "fetch news?"
    question, no update check (with fetchNews alone the page still asked PyPI through the
    server)."""
    import json
    import sys
    from pathlib import Path

    from nfarm.infra.paths import ROOT

    installed = Path(sys.prefix) / "share" / "jupyter" / "lab" / "settings" / "overrides.json"
    ours = json.loads((ROOT / "jupyter" / "lab-overrides.json").read_text())
    assert ours["@jupyterlab/apputils-extension:notification"] == {"fetchNews": "false", "checkForUpdates": False}
    assert json.loads(installed.read_text()) == ours
