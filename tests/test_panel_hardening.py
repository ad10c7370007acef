"""Issue 46's hardening of the panel: the server answers only this machine's pages (Host checked,
a token), its kernels are bounded, the recordings grow linearly and are checked against a
limit before writing, every value typed or passed to the panel's computations is one line,
and a failed action leaves nothing of the one before it on the page."""

from __future__ import annotations

import html
import http.client
import json
import os
import re
import signal
import socket
import subprocess
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from nfarm.publishing import panel_compute as pc
from nfarm.publishing.panel_app import local_host
from nfarm.publishing.panel_server import new_token, panel_url, voila_command, voila_environment

TINY_NOTEBOOK = {
    "cells": [{"cell_type": "code", "execution_count": None, "metadata": {}, "outputs": [],
               "source": ["print('the tiny panel')"]}],
    "metadata": {"kernelspec": {"display_name": "nfarm", "language": "python", "name": "nfarm"}},
    "nbformat": 4, "nbformat_minor": 5}


def one_line(text: str) -> str:
    """A page's message row as the reader sees it."""
    return html.unescape(re.sub(r"<[^>]+>", "", text))


# -- the server ----------------------------------------------------------------------------------


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    """The panel's server (as ``make panel`` starts it) on a tiny notebook: a kernel starts in
    about a second, and what is checked is the server's, not the notebook's."""

    def __init__(self, directory: Path, **limits):
        self.port, self.token = free_port(), new_token()
        notebook = directory / "tiny.ipynb"
        notebook.write_text(json.dumps(TINY_NOTEBOOK))
        self.log = directory / "voila.log"
        with open(self.log, "w") as log:
            self.proc = subprocess.Popen(voila_command(self.port, notebook, connection_dir=directory, **limits),
                                         env=voila_environment(directory, self.token), stdout=log,
                                         stderr=subprocess.STDOUT, start_new_session=True)
        deadline = time.monotonic() + 120
        while self.request("/voila/static/voila.js", token=False)[0] != 200:
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.stop()
                pytest.fail(f"the panel's server did not start: {self.log.read_text()[-2000:]}")
            time.sleep(0.25)

    def request(self, path: str, *, token: bool = True, host: str | None = None, method: str = "GET",
                headers: dict | None = None) -> tuple[int, dict, str]:
        """``(status, headers, body)`` of one request, redirects not followed."""
        if token:
            path += ("&" if "?" in path else "?") + f"token={self.token}"
        connection = http.client.HTTPConnection("127.0.0.1", self.port, timeout=60)
        try:
            connection.putrequest(method, path, skip_host=True)
            connection.putheader("Host", host or f"127.0.0.1:{self.port}")
            for key, value in (headers or {}).items():
                connection.putheader(key, value)
            connection.endheaders()
            response = connection.getresponse()
            return response.status, dict(response.getheaders()), response.read().decode("utf-8", "replace")
        except OSError:
            return 0, {}, ""
        finally:
            connection.close()

    def page(self) -> tuple[int, str]:
        """Load the page with the token: its status and its kernel's id ("" when none)."""
        status, _, body = self.request("/")
        found = re.search(r'"kernelId":\s*"([0-9a-f-]+)"', body)
        return status, found.group(1) if found else body

    def stop(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGTERM)        # Voilà shuts its kernels down and exits
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """One page at a time, no culling (the kernel limit and the page's own shutdown are seen)."""
    running = Server(tmp_path_factory.mktemp("panel-server"), max_kernels=1, cull_idle_s=0)
    yield running
    running.stop()


WEBSOCKET = {"Connection": "Upgrade", "Upgrade": "websocket", "Sec-WebSocket-Version": "13",
             "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ=="}


def test_the_server_answers_only_its_own_machine_and_the_token(server):
    port = server.port
    # A DNS-rebinding page: its requests carry its own domain in Host, and are refused, page,
    # static files and kernels alike, token or not.
    for host in (f"evil.example:{port}", "evil.example", f"127.0.0.1.nip.io:{port}", f"localhost.evil:{port}"):
        for path in ("/", "/voila/static/voila.js", "/api/kernels/0"):
            status = server.request(path, host=host)[0]
            assert status in (400, 403), (host, path, status)
    # Without the token (or with another): no page (the login form instead), no kernel, no
    # websocket, no shutdown.
    for path in ("/", f"/?token={new_token()}"):
        status, headers, body = server.request(path, token=False)
        assert status in (302, 403) and "the tiny panel" not in body
        if status == 302:
            assert headers["Location"].startswith("/login")
    status, kernel = server.page()
    assert status == 200 and re.fullmatch(r"[0-9a-f-]{36}", kernel), kernel
    assert server.request(f"/api/kernels/{kernel}", token=False)[0] == 403
    assert server.request(f"/api/kernels/{kernel}/channels", token=False, headers=WEBSOCKET)[0] == 403
    assert server.request(f"/voila/api/shutdown/{kernel}", token=False, method="POST")[0] == 403
    # With the token, on any localhost name, it is served.
    status, _, body = server.request(f"/api/kernels/{kernel}", host=f"localhost:{port}")
    assert status == 200 and json.loads(body)["id"] == kernel
    # The page's kernel ends when the page closes (the page posts this), freeing its place.
    assert server.request(f"/voila/api/shutdown/{kernel}", method="POST")[0] == 204
    assert server.request(f"/api/kernels/{kernel}")[0] == 404


def test_a_page_beyond_the_kernel_limit_is_refused_in_one_line(server):
    status, first = server.page()
    assert status == 200
    try:
        status, _, body = server.request("/")
        assert status == 503
        text = one_line(body)
        assert "its limit of 1" in text and "close a page" in text
    finally:
        assert server.request(f"/voila/api/shutdown/{first}", method="POST")[0] == 204
    assert server.page()[0] == 200


def test_an_idle_kernel_without_a_page_is_culled(tmp_path):
    culling = Server(tmp_path, max_kernels=2, cull_idle_s=2, cull_interval_s=1)
    try:
        status, kernel = culling.page()           # loaded, never connected: a page that went away
        assert status == 200
        deadline = time.monotonic() + 60
        while culling.request(f"/api/kernels/{kernel}")[0] == 200 and time.monotonic() < deadline:
            time.sleep(0.5)
        assert culling.request(f"/api/kernels/{kernel}")[0] == 404
    finally:
        culling.stop()
    assert "Culling" in culling.log.read_text()


@pytest.mark.parametrize("host, ok", [("127.0.0.1", True), ("127.0.0.1:8866", True), ("127.5.6.7:1", True),
                                      ("localhost:8866", True), ("LOCALHOST", True), ("[::1]:8866", True),
                                      ("evil.example:8866", False), ("127.0.0.1.evil.example", False),
                                      ("0.0.0.0:8866", False), ("[::]:8866", False), ("", False),
                                      ("192.168.1.2:8866", False), ("localhost.:8866", False)])
def test_only_loopback_names_are_local(host, ok):
    assert local_host(host) is ok


def test_the_printed_address_holds_a_fresh_token():
    a, b = new_token(), new_token()
    assert a != b and len(a) >= 43 and re.fullmatch(r"[A-Za-z0-9_-]+", a)
    assert panel_url(8866, a) == f"http://127.0.0.1:8866/?token={a}"
    command = voila_command(8866)
    assert not any("allow_remote_access" in part or "token" in part.lower() for part in command)
    with pytest.raises(ValueError, match="max_kernels"):
        voila_command(8866, max_kernels=0)
    with pytest.raises(ValueError, match="token"):
        voila_environment(Path("/tmp"), "")


# -- the command line ----------------------------------------------------------------------------


def test_panel_start_up_errors_are_one_line_before_any_address(tmp_path, monkeypatch, capsys):
    from nfarm import __main__ as cli
    from nfarm.publishing import panel_server

    def not_here(*args):
        raise AssertionError("the panel went on to start Voilà in the test process")

    monkeypatch.setattr(os, "execve", not_here)
    (tmp_path / "panel").write_text("a file where the server's directory goes")
    monkeypatch.setattr(panel_server, "BUILD", tmp_path)
    assert cli.panel_command(free_port()) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1
    assert "panel/jupyter" in err and "is a file, not a directory" in err


# -- the panel's values --------------------------------------------------------------------------

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from nfarm.learning.learned import LearnedIK
    from nfarm.learning.learned_id import LearnedID
    from nfarm.model.kinematics import fk
    from nfarm.model.robot import load_robot
    from nfarm.presentation.recording import RecordingTooLarge, expected_bytes, record_trajectory
    from nfarm.publishing.panel import ArmPanel

    ROBOT = load_robot(pc.shipped_robots()["intelbot5"])
    OTHER = load_robot(pc.shipped_robots()["so101"])
Z = [0.0] * ROBOT.n


@pytest.fixture(scope="module")
def panel(tmp_path_factory):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ArmPanel("intelbot5", models_dir=tmp_path_factory.mktemp("no-models"),
                        recordings_dir=tmp_path_factory.mktemp("recordings"))


def set_trajectory(page, *, q0=Z, qf=(30.0,) * 5, v0=Z, vf=Z, t0=0.0, dt=0.2, tf=6.0, profile="cubic"):
    for boxes, values in ((page.q0, q0), (page.qf, qf), (page.v0, v0), (page.vf, vf)):
        for box, value in zip(boxes, values):
            box.value = value
    page.t0.value, page.dt.value, page.tf.value, page.profile.value = t0, dt, tf, profile


def shows_nothing_old(panel) -> bool:
    page, dynamics = panel.trajectory, panel.dynamics
    return (page.trajectory is None and dynamics.parts is None and dynamics.peaks.value == ""
            and not any(ax.lines for ax in [*page.axes, *dynamics.axes])
            and np.size(page.view.path.get_data_3d()[0]) == 0 and page.frame.max == 0)


@pytest.mark.parametrize("values, says", [
    (dict(tf=1e-100, dt=1e-101, profile="quintic"), "below the bound of 0.001 s"),
    (dict(tf=1e-160, dt=1e-161), "below the bound of 0.001 s"),
    (dict(tf=1e80, dt=1e76), "end time: 1e+80 s is over the bound of 1e+06 s"),
    (dict(t0=-1e300), "start time: -1e+300 s is below the bound of -1e+06 s"),
    (dict(qf=(1e300,) * 5), "final position [deg]: 1e+300 for base_yaw is beyond the bound of ±3600"),
    (dict(v0=(0, 1e200, 0, 0, 0), profile="quintic"), "initial velocity [deg/s]: 1e+200 for shoulder_pitch"),
    (dict(vf=(0, 0, 0, 0, -2e5)), "final velocity [deg/s]: -200000 for wrist_roll is beyond the bound of ±100000"),
    (dict(dt=5e-324), "gives more than 1e308 samples"),
    (dict(dt=np.nan), "time step: a finite number needed, got nan"),
])
def test_trajectory_values_beyond_their_bounds_are_one_line_and_clear_the_page(panel, values, says):
    page = panel.trajectory
    set_trajectory(page)
    page.compute()
    assert page.trajectory is not None and panel.dynamics.parts is not None
    set_trajectory(page, **values)
    page.buttons["compute"].click()
    message = one_line(page.message.value)
    assert says in message and "\n" not in message and "np.float64" not in message, message
    assert shows_nothing_old(panel)
    # "save" now records nothing, not the trajectory before
    page.save_button.click()
    assert "compute a trajectory first" in one_line(page.message.value)
    set_trajectory(page)


@pytest.mark.parametrize("values", [
    dict(tf=1e-3, dt=1e-3 / 4, qf=(3600,) * 5, v0=(1e5,) * 5, vf=(-1e5,) * 5, profile="quintic"),
    dict(tf=1e-3, dt=1e-4, qf=(-3600,) * 5, v0=(-1e5,) * 5),
    dict(t0=-1e6, tf=1e6, dt=1e2, qf=(3600,) * 5, vf=(1e5,) * 5, profile="quintic"),
    dict(t0=1e6 - 1e-3, tf=1e6, dt=1e-5),
])
def test_no_nan_reaches_a_table_or_a_plot_within_the_bounds(panel, values):
    page = panel.trajectory
    set_trajectory(page, **values)
    page.compute()
    assert page.message.value == "" and panel.dynamics.message.value == ""
    tr, parts = page.trajectory, panel.dynamics.parts
    for values_ in (tr.t, tr.q, tr.qd, tr.qdd, parts.total, parts.inertial, parts.coriolis, parts.gravity):
        assert np.isfinite(values_).all()
    for ax in [*page.axes, *panel.dynamics.axes]:
        for line in ax.lines:
            assert np.isfinite(np.asarray(line.get_ydata(), dtype=float)).all()
    assert "nan" not in panel.dynamics.peaks.value.lower() and "inf" not in panel.dynamics.peaks.value.lower()
    set_trajectory(page)


def test_a_failed_save_says_so_and_leaves_the_saved_file(panel, tmp_path):
    page = panel.trajectory
    set_trajectory(page)
    page.compute()
    page.save_button.click()
    path = panel.recordings_dir / "intelbot5-panel-trajectory.rrd"
    saved = path.read_bytes()
    limit, panel.max_recording_bytes = panel.max_recording_bytes, 200_000
    try:
        page.save_button.click()
    finally:
        panel.max_recording_bytes = limit
    message = one_line(page.message.value)
    assert message.startswith("recording: ") and "\n" not in message
    assert "31 samples would take about 0.3 MiB, over the limit of 0.2 MiB" in message and "nothing written" in message
    assert path.read_bytes() == saved and [p.name for p in path.parent.iterdir()] == [path.name]


# -- recordings ----------------------------------------------------------------------------------


def recorded_size(tmp_path, samples: int, **options) -> int:
    tr, _ = pc.joint_trajectory(ROBOT, Z, [30.0] * 5, Z, Z, dt=6.0 / samples, max_samples=samples + 2)
    tau = pc.torque_parts(ROBOT, tr).total
    path = record_trajectory(ROBOT, tr, tmp_path / f"r{samples}.rrd", tau=tau, **options)
    size = path.stat().st_size
    assert size <= expected_bytes(len(tr.t), transforms=5, scalars=15)
    return size


def test_a_recording_grows_linearly_with_its_samples(tmp_path):
    """The tool path was a strip of every point so far at every step (K(K + 1)/2 points: the
    size's second difference as large as its first); now one segment a step."""
    s1, s2, s4 = (recorded_size(tmp_path, k) for k in (1000, 2000, 4000))
    assert (s4 - s2) / (s2 - s1) < 2.5          # linear: 2; the old quadratic path: 3.8


def test_a_recording_over_its_limit_is_refused_before_writing(tmp_path):
    with pytest.raises(RecordingTooLarge) as refused:
        recorded_size(tmp_path, 20_000, max_bytes=2**20)
    message = str(refused.value)
    assert "\n" not in message and "20,001 samples would take about 12.8 MiB, over the limit of 1.0 MiB" in message
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ValueError, match="max_bytes must be a positive whole number"):
        recorded_size(tmp_path, 100, max_bytes=0)


# -- the panel's computations called from Python -------------------------------------------------


def other_robots_model(cls):
    """A model as fitting it for the SO-101 leaves it (what the check reads), without the fit."""
    from nfarm.model.robot import robot_hash

    model = cls()
    model.robot_hash_, model.robot_name_, model.n_joints_ = robot_hash(OTHER), OTHER.name, OTHER.n
    return model


T_HOME = fk(ROBOT, np.zeros(5))
FAR = T_HOME.copy()
FAR[:3, 3] = 1e158
TRAJECTORY = pc.joint_trajectory(ROBOT, Z, [30.0] * 5, Z, Z)[0]


@pytest.mark.parametrize("call, says", [
    (lambda: pc.ik_answers(ROBOT, T_HOME, learned=other_robots_model(LearnedIK)), "learned: the model was trained for the robot"),
    (lambda: pc.torque_parts(ROBOT, TRAJECTORY, learned=other_robots_model(LearnedID)), "learned: the model was trained for the robot"),
    (lambda: pc.torque_parts(ROBOT, TRAJECTORY, learned=LearnedID()), "learned: the LearnedID is not fitted"),
    (lambda: pc.torque_parts(ROBOT, TRAJECTORY, learned="model"), "learned: a LearnedID or None needed, got str"),
    (lambda: pc.torque_parts(ROBOT, TRAJECTORY, chunk=-1), "chunk: a whole number >= 1 needed, got -1"),
    (lambda: pc.torque_parts(ROBOT, TRAJECTORY, chunk=0), "chunk: a whole number >= 1 needed, got 0"),
    (lambda: pc.torque_parts(ROBOT, TRAJECTORY, chunk=np.float64(8)), "chunk: a whole number >= 1 needed, got float64 8"),
    (lambda: pc.torque_parts(ROBOT, "trajectory"), "trajectory: a Trajectory (joint_trajectory) needed, got str"),
    (lambda: pc.ik_answers(ROBOT, np.stack([T_HOME, T_HOME])), "target pose: one pose of shape (4, 4) needed, got shape (2, 4, 4)"),
    (lambda: pc.ik_answers(ROBOT, None), "target pose: numbers needed, got None"),
    (lambda: pc.ik_answers(ROBOT, b"\x00" * 16), "target pose: numbers needed, got b'"),
    (lambda: pc.ik_answers(ROBOT, "T_HOME"), "target pose: numbers needed, got 'T_HOME'"),
    (lambda: pc.ik_answers(ROBOT, T_HOME + 0j), "target pose: real numbers needed, got complex numbers"),
    (lambda: pc.ik_answers(ROBOT, np.where(np.eye(4) > 0, np.nan, T_HOME)), "target pose: finite numbers needed, got [nan"),
    (lambda: pc.ik_answers(ROBOT, T_HOME.tolist()[:3]), "target pose: one pose of shape (4, 4) needed, got shape (3, 4)"),
    (lambda: pc.ik_answers(ROBOT, FAR), "target pose: its position lies 1.73e+158 m from the arm's base, over the bound of"),
    (lambda: pc.ik_answers(ROBOT, T_HOME, tol_mm=np.nan), "tol_mm: a finite number needed, got nan"),
    (lambda: pc.ik_answers(ROBOT, T_HOME, tol_mm=-0.1), "tol_mm: must be > 0, got -0.1 mm"),
    (lambda: pc.ik_answers(ROBOT, T_HOME, tol_deg="0.1"), "tol_deg: a real number needed, got str '0.1'"),
    (lambda: pc.ik_answers(ROBOT, T_HOME, seed=-1), "seed: a whole number >= 0 needed, got -1"),
    (lambda: pc.joint_trajectory(ROBOT, Z, Z, Z, Z, dt="0.2"), "time step: a real number needed, got str '0.2'"),
    (lambda: pc.joint_trajectory(ROBOT, Z, Z, Z, Z, tf=np.float64(1.0), t0=np.float64(1.0)), "end time 1 s must be after the start time 1 s"),
    (lambda: pc.joint_trajectory(ROBOT, [1j] * 5, Z, Z, Z), "initial position [deg]: real numbers needed, got complex"),
    (lambda: pc.joint_trajectory(ROBOT, None, Z, Z, Z), "initial position [deg]: numbers needed, got None"),
    (lambda: pc.joint_trajectory(ROBOT, Z, b"12345", Z, Z), "final position [deg]: numbers needed, got b'12345'"),
    (lambda: pc.joint_trajectory(ROBOT, Z, Z, [np.float64(np.nan)] * 5, Z), "initial velocity [deg/s]: finite numbers needed, got [nan, nan"),
    (lambda: pc.joint_trajectory(ROBOT, Z, Z, Z, Z[:4]), "final velocity [deg/s]: shape (5,) needed, got (4,)"),
    (lambda: pc.joint_trajectory(ROBOT, Z, Z, Z, Z, profile=None), "profile: one of cubic, quintic, got None"),
    (lambda: pc.joint_trajectory(ROBOT, Z, Z, Z, Z, max_samples=True), "max_samples: a whole number >= 2 needed, got bool True"),
    (lambda: pc.pose_readout(ROBOT, [np.nan] * 5), "configuration q [rad]: finite numbers needed, got [nan"),
    (lambda: pc.pose_readout(ROBOT, "0 0 0 0 0"), "configuration q [rad]: numbers needed, got '0 0 0 0 0'"),
    (lambda: pc.target_pose([np.float64(np.nan), 0, 0], Z[:3]), "target position [mm]: finite numbers needed, got [nan, 0, 0]"),
    (lambda: pc.target_pose(Z[:3], "abc"), "target roll, pitch, yaw [deg]: numbers needed, got 'abc'"),
    (lambda: pc.parse_pose_matrix("1 0 0 0; 0 1 0 0; 0 0 1 0; 1e-9 0 0 1"), "the fourth row must be exactly 0 0 0 1, got 1e-09 0 0 1"),
    (lambda: pc.parse_pose_matrix("1 0 0 0_0; 0 1 0 0; 0 0 1 0"), "typed pose: '0_0' is not a number"),
    (lambda: pc.parse_pose_matrix("1 0 0 nan; 0 1 0 0; 0 0 1 0"), "typed pose: 'nan' is not a number"),
    (lambda: pc.parse_pose_matrix("１ 0 0 0; 0 1 0 0; 0 0 1 0"), "typed pose: '１' is not a number"),
    (lambda: pc.parse_pose_matrix("1 0 0 1e999; 0 1 0 0; 0 0 1 0"), "typed pose: finite numbers needed, got [inf]"),
    (lambda: pc.parse_pose_matrix(None), "typed pose: text needed, got NoneType"),
])
def test_the_panels_computations_refuse_bad_arguments_in_their_own_line(call, says):
    with pytest.raises(pc.PanelInputError) as refused:
        call()
    message = str(refused.value)
    assert says in message, message
    assert "\n" not in message and "np.float64" not in message and "q0" not in message


def test_messages_show_numbers_as_they_read():
    assert pc.shown(np.float64(1.0)) == "1" and pc.shown(np.int64(3)) == "3"
    assert pc.shown([np.float64(0.25), np.float32(np.inf)]) == "[0.25, inf]"
    assert pc.shown(np.arange(10.0)) == "[0, 1, 2, 3, 4, 5, 6, 7, …]"


@pytest.mark.parametrize("out, says", [
    ("README.md", "--out: README.md exists and is not a directory"),
    ("README.md/course", "lies under"),
    ("/proc/self/course", "lies in /proc, a system directory"),
    ("/dev/null", "--out: /dev/null exists and is not a directory"),
    ("unwritable/course", "cannot be written (no permission in"),
])
def test_course_out_is_checked_as_the_other_commands_check_theirs(out, says, tmp_path, monkeypatch, capsys):
    from nfarm import __main__ as cli
    from nfarm.infra.paths import ROOT
    from nfarm.publishing import course

    def not_built(*args, **kwargs):
        raise AssertionError("the course was built")

    monkeypatch.setattr(course, "build_course", not_built)
    monkeypatch.chdir(ROOT)
    if out.startswith("unwritable"):
        (tmp_path / "unwritable").mkdir()
        out = str(tmp_path / out)
        real = os.access
        monkeypatch.setattr(os, "access", lambda p, mode: False if Path(p) == tmp_path / "unwritable" else real(p, mode))
    assert cli.main(["course", "--no-teacher", "--out", out]) == 2
    err = capsys.readouterr().err
    assert err.startswith("course: --out: ") and says in err and err.count("\n") == 1


def test_the_command_line_loads_the_library_only_in_its_commands():
    """A Ctrl-C while the library loads (the first second of a sweep) meets the one line of
    ``nfarm: interrupted``, not a traceback through the imports: ``__main__`` imports nothing of
    the library at its top, only inside the commands that ``_main`` runs."""
    import ast

    from nfarm.infra.paths import ROOT

    tree = ast.parse((ROOT / "lib" / "nfarm" / "__main__.py").read_text())
    top = [node for node in tree.body if isinstance(node, ast.ImportFrom) and (node.level or 0) > 0]
    assert not top, [ast.unparse(node) for node in top]
