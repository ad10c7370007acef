"""The arm panel: the dissertation's interactive program ("Intelbot") as widgets.

Four pages, as the dissertation's program: **forward kinematics** (a slider per joint, the arm in 3-D,
the tool's pose), **inverse kinematics** (a target pose answered by the closed form's every
branch, Levenberg–Marquardt and the learned ANFIS side by side; an answer goes on to the
trajectory as its final position), **trajectory** (cubic or quintic between two
configurations, plotted and animated, saved as a rerun recording) and **inverse dynamics**
(Newton–Euler torques along it, split into their parts, beside the learned model's).

Open it in JupyterLab (``make lab``, ``notebooks/arm_panel.ipynb``) or as a local web page
(``make panel``, Voilà)::

    from nfarm.publishing.panel import Panel
    Panel("intelbot5").widget          # the last expression of a cell shows it

The numbers come from :mod:`nfarm.publishing.panel_compute`; this module lays them out. The 3-D views are
ipympl canvases made explicitly (the figure never enters pyplot's state), drawn by Agg in the
kernel and sent as image differences: a slider move updates the drawn lines' data and asks the
page to redraw (``benchmarks/bench_panel.py`` measures it). Every callback shows a bad input as
one line in its page's message row; nothing raises into the page.
"""

from __future__ import annotations

import functools
import html
import sys
import warnings
from collections.abc import Callable
from pathlib import Path

import ipywidgets as w
import numpy as np
from matplotlib.figure import Figure


def _ipympl_canvas_classes():
    """ipympl's canvas widget and figure manager, without ipympl's import side effect: its
    ``__init__`` makes itself pyplot's backend when matplotlib is loaded, and switching pyplot's
    backend closes every open figure (a chapter's, a test's). The panel draws on canvases it
    makes itself and needs no pyplot backend."""
    if "ipympl" not in sys.modules:
        loaded = sys.modules.pop("matplotlib")
        try:
            import ipympl  # noqa: F401 — sees no matplotlib, so leaves the backend alone
        finally:
            sys.modules["matplotlib"] = loaded
    from ipympl.backend_nbagg import Canvas, FigureManager
    return Canvas, FigureManager


Canvas, FigureManager = _ipympl_canvas_classes()

from ..model.kinematics import fk, fk_all
from .panel_compute import (PROFILES, PanelInputError, ik_answers, joint_trajectory, parse_pose_matrix,
                            pose_readout, shipped_robots, target_pose, torque_parts, trained_models)
from ..infra.paths import BUILD, shown_path
from ..model.robot import Robot, is_robot_name, load_robot, sample_configurations
from ..model.rotations import matrix_to_rpy
from ..presentation.recording import RecordingTooLarge, record_trajectory

__all__ = ["Panel", "ArmPanel"]

_TRIAD = ("r", "g", "b")     # the tool frame's x, y, z axes, as in the report's figures
_ERROR = "color:#b00020"
_NOTE = "color:#6a4f00"


def _canvas(fig: Figure) -> Canvas:
    """An ipympl canvas widget for ``fig``, with its manager (which draws on the page's
    request) and no header, footer or resize handle."""
    canvas = Canvas(fig)
    with warnings.catch_warnings():
        # ipympl's toolbar passes matplotlib's argument on to traitlets, which warns (ipympl 0.10)
        warnings.filterwarnings("ignore", "Passing unrecognized arguments", DeprecationWarning)
        FigureManager(canvas, 0)
    canvas.header_visible = canvas.footer_visible = canvas.resizable = False
    canvas.toolbar_visible = "fade-in-fade-out"
    return canvas


def _figure(width: float, height: float) -> tuple[Figure, Canvas]:
    """A figure on its own ipympl canvas widget (not registered with pyplot)."""
    fig = Figure(figsize=(width, height), dpi=90, layout="constrained")
    canvas = _canvas(fig)
    return fig, canvas


def _line(text: str, style: str = "") -> str:
    return f'<span style="{style}">{html.escape(text)}</span>' if text else ""


def _table(header: list[str], rows: list[list[str]]) -> str:
    """An HTML table: the first column (names) left-aligned and unbroken, numbers right-aligned."""
    def cell(tag: str, k: int, text: str) -> str:
        align = "left;white-space:nowrap" if k == 0 else "left" if header[k] == "note" else "right"
        return f"<{tag} style='padding:1px 8px;line-height:1.35;text-align:{align}'>{text}</{tag}>"

    head = "".join(cell("th", k, html.escape(h)) for k, h in enumerate(header))
    body = "".join("<tr>" + "".join(cell("td", k, c) for k, c in enumerate(row)) + "</tr>" for row in rows)
    return f"<table style='border-collapse:collapse;font-family:monospace;font-size:12px'><tr>{head}</tr>{body}</table>"


def _small(value: float, floor: float = 1e-6) -> str:
    """A tool error [mm or deg]: below ``floor`` (the solvers' tolerances, 1e-9 m and rad, lie
    below it) it is rounding, shown as such."""
    return f"< {floor:g}" if value < floor else f"{value:.3g}"


def shows_errors(method: Callable) -> Callable:
    """Run a page's callback; a bad input (or anything unexpected) becomes one line in the
    page's ``message`` widget instead of a traceback in the page."""
    @functools.wraps(method)
    def run(self, *args, **kwargs):
        self.message.value = ""
        try:
            return method(self, *args, **kwargs)
        except PanelInputError as error:
            self.message.value = _line(str(error), _ERROR)
        except Exception as error:     # noqa: BLE001 — the page must stay usable; say what happened
            first = (str(error).strip().splitlines() or [""])[0]
            self.message.value = _line(f"{type(error).__name__}: {first}", _ERROR)
    return run


class _ArmView:
    """A 3-D drawing of the arm whose lines are moved, not redrawn: links through the DH frame
    origins, the joints as dots, the tool frame as a red-green-blue triad, and a tool path.

    The lines are animated artists blitted over a cached background (axes, panes, ticks,
    legend): a pose change redraws only them, 4–5 times less work than the move with a full 3-D
    draw (``benchmarks/bench_panel.py``). A full draw (the page asks for one when it opens, or
    when the reader turns the view) renders the background and captures it again. The figure
    has a fixed layout: constrained layout took a third of a full draw (58 of 164 ms, profiled).
    """

    def __init__(self, robot: Robot, q: np.ndarray, *, size: tuple[float, float] = (5.0, 4.6),
                 with_path: bool = False):
        self.robot = robot
        self.fig = Figure(figsize=size, dpi=90)
        self.canvas = _canvas(self.fig)
        ax = self.ax = self.fig.add_axes((0.0, 0.02, 0.95, 0.96), projection="3d")
        # The box: the arm's reach about its base, from its frames' origins in 512 configurations.
        base = robot.base[:3, 3]
        points = fk_all(robot, sample_configurations(robot, 512, seed=0))[..., :3, 3].reshape(-1, 3)
        r = self.scale = 1.05 * float(np.linalg.norm(points - base, axis=1).max())
        z_lo = min(float(points[:, 2].min()), base[2]) - 0.05 * r
        ax.set(xlim=(base[0] - r, base[0] + r), ylim=(base[1] - r, base[1] + r),
               zlim=(z_lo, base[2] + r), xlabel="x [m]", ylabel="y [m]", zlabel="z [m]")
        ax.set_box_aspect((2, 2, (base[2] + r - z_lo) / r), zoom=0.92)
        ax.view_init(elev=22, azim=-60)
        ax.tick_params(labelsize=7)
        style = dict(animated=True)
        self.links, = ax.plot([], [], [], "-", color="C0", lw=3, solid_capstyle="round", label="links", **style)
        self.joints, = ax.plot([], [], [], "o", color="k", ms=4, label="joints (DH frame origins)", **style)
        self.triad = [ax.plot([], [], [], color=c, lw=1.5, label=f"tool {a} axis", **style)[0]
                      for c, a in zip(_TRIAD, "xyz")]
        self.path, = ax.plot([], [], [], "--", color="C1", lw=1, label="tool path" if with_path else None, **style)
        self.travelled, = ax.plot([], [], [], "-", color="C1", lw=2,
                                  label="tool path so far" if with_path else None, **style)
        self.artists = [self.path, self.travelled, self.links, self.joints, *self.triad]
        self.fig.legend(loc="upper left", fontsize=7, ncols=2, frameon=False)
        self.background = None
        self.canvas.mpl_connect("draw_event", self._drawn)
        self.show(q)

    def _drawn(self, event) -> None:
        """After a full draw: keep the background, draw the lines over it."""
        self.background = self.canvas.copy_from_bbox(self.fig.bbox)
        self._draw_lines()

    def _draw_lines(self) -> None:
        for artist in self.artists:
            self.ax.draw_artist(artist)

    def update(self) -> None:
        """Show the lines' new data: blit them over the background, or ask for a full draw
        when there is none yet."""
        if self.background is None:
            self.canvas.draw_idle()
            return
        self.canvas.restore_region(self.background)
        self._draw_lines()
        self.canvas.blit(self.fig.bbox)

    def show(self, q: np.ndarray, *, travelled: np.ndarray | None = None) -> None:
        frames = fk_all(self.robot, q)
        T = fk(self.robot, q)
        points = np.vstack([frames[:, :3, 3], T[:3, 3]])
        self.links.set_data_3d(*points.T)
        self.joints.set_data_3d(*frames[:, :3, 3].T)
        for axis, line in zip(T[:3, :3].T, self.triad):
            line.set_data_3d(*np.column_stack([T[:3, 3], T[:3, 3] + 0.15 * self.scale * axis]))
        if travelled is not None:
            self.travelled.set_data_3d(*travelled.T)
        self.update()

    def show_path(self, points: np.ndarray | None) -> None:
        empty = np.empty((0, 3))
        self.path.set_data_3d(*(empty if points is None else points).T)
        self.travelled.set_data_3d(*empty.T)


# --------------------------------------------------------------------------------------------
# Pages


class FKPage:
    """Forward kinematics: one slider per joint [deg] within its limits, the arm in 3-D and the
    tool's pose (position [mm], rotation matrix, roll-pitch-yaw, quaternion), the manipulability
    and a warning near a singularity."""

    title = "Forward kinematics"

    def __init__(self, panel: "ArmPanel"):
        self.panel = panel
        robot = panel.robot
        self.message = w.HTML()
        lo, hi = np.degrees(robot.qlim).T
        self.sliders = [w.FloatSlider(value=float(np.clip(0.0, a, b)), min=float(a), max=float(b), step=0.5,
                                      description=f"{name} [deg]", readout_format=".1f", continuous_update=True,
                                      style={"description_width": "140px"}, layout=w.Layout(width="430px"))
                        for name, a, b in zip(robot.joint_names, lo, hi)]
        self.home = w.Button(description="home (q = 0)", tooltip="every joint to 0°, or its nearest limit")
        self.home.on_click(lambda _: self.set_q(np.zeros(robot.n)))
        self.readout = w.HTML()
        self.warning = w.HTML()
        self._holding = False
        self.view = _ArmView(robot, self.q)
        for s in self.sliders:
            s.observe(self._moved, names="value")
        self._moved()
        controls = w.VBox([*self.sliders, self.home, self.readout, self.warning, self.message])
        self.widget = w.HBox([controls, self.view.canvas])

    @property
    def q(self) -> np.ndarray:
        """The sliders' configuration ``(n,)`` [rad]."""
        return np.radians([s.value for s in self.sliders])

    def set_q(self, q) -> None:
        """Move the sliders to ``q (n,)`` [rad] (clipped to the limits) and redraw once."""
        self._holding = True
        try:
            for s, value in zip(self.sliders, np.degrees(np.asarray(q, dtype=float))):
                s.value = float(np.clip(value, s.min, s.max))
        finally:
            self._holding = False
        self._moved()

    @shows_errors
    def _moved(self, change=None) -> None:
        if self._holding:
            return
        q = self.q
        r = pose_readout(self.panel.robot, q, near_singular=self.panel.near_singular)
        R = r.T_0e[:3, :3]
        rows = [["position [mm]", *(f"{v:.2f}" for v in r.position_mm), ""],
                ["roll, pitch, yaw [deg]", *(f"{v:.2f}" for v in r.rpy_deg), ""],
                ["quaternion w, x, y, z", *(f"{v:.4f}" for v in r.quat)],
                *[["rotation matrix R" if i == 0 else "", *(f"{v + 0.0:.4f}" for v in R[i]), ""] for i in range(3)],
                ["manipulability w [m³]", f"{r.manipulability:.3e}", "", "", ""],
                ["σ_min position [mm/rad]", f"{r.sigma_position_m * 1e3:.3g}", "", "", ""]]
        self.readout.value = _table(["tool pose", "", "", "", ""], rows)
        self.warning.value = _line(r.warning, _NOTE)
        self.view.show(q)


class IKPage:
    """Inverse kinematics: a target pose (typed as position and roll-pitch-yaw or as a matrix,
    taken from the arm, or nudged) answered by every method side by side; an answer can be shown
    on the arm or sent to the trajectory page as its final position."""

    title = "Inverse kinematics"
    _FIELDS = ("x [mm]", "y [mm]", "z [mm]", "roll [deg]", "pitch [deg]", "yaw [deg]")

    def __init__(self, panel: "ArmPanel"):
        self.panel = panel
        self.message = w.HTML()
        self.fields = [w.FloatText(description=name, layout=w.Layout(width="200px"),
                                   style={"description_width": "90px"}) for name in self._FIELDS]
        self.step_mm = w.BoundedFloatText(value=10.0, min=0.0, max=1e4, description="nudge [mm]",
                                          layout=w.Layout(width="200px"), style={"description_width": "90px"})
        self.step_deg = w.BoundedFloatText(value=5.0, min=0.0, max=180.0, description="nudge [deg]",
                                           layout=w.Layout(width="200px"), style={"description_width": "90px"})
        rows = []
        self.nudge_buttons = {}      # (field index, −1 or +1) -> button
        for k, field in enumerate(self.fields):
            for sign, label in ((-1, "−"), (1, "+")):
                button = self.nudge_buttons[k, sign] = w.Button(description=label, layout=w.Layout(width="36px"),
                                                                tooltip=f"{label} one nudge step in {self._FIELDS[k]}")
                button.on_click(functools.partial(self._nudge, k, sign))
            rows.append(w.HBox([field, self.nudge_buttons[k, -1], self.nudge_buttons[k, 1]]))
        self.mode = w.ToggleButtons(options=["position and roll-pitch-yaw", "typed matrix"],
                                    style={"button_width": "190px"})
        self.matrix = w.Textarea(placeholder="r11 r12 r13 x_mm; r21 r22 r23 y_mm; r31 r32 r33 z_mm",
                                 layout=w.Layout(width="420px", height="70px"))
        self.from_arm = w.Button(description="target ← arm", tooltip="the forward-kinematics page's tool pose")
        self.from_arm.on_click(self._from_arm)
        self.solve_button = w.Button(description="solve", button_style="primary")
        self.solve_button.on_click(lambda _: self.solve())
        self.progress = w.IntProgress(min=0, max=3, layout=w.Layout(width="200px", visibility="hidden"))
        self.answers_html = w.HTML()
        self.choice = w.Dropdown(description="answer", options=[], layout=w.Layout(width="420px"))
        self.show_button = w.Button(description="show on arm")
        self.show_button.on_click(self._show)
        self.send_button = w.Button(description="send to trajectory as final position", layout=w.Layout(width="auto"))
        self.send_button.on_click(self._send)
        self.answers: list = []
        self.widget = w.VBox([
            w.HBox([w.VBox(rows[:3] + [self.step_mm]), w.VBox(rows[3:] + [self.step_deg])]),
            self.mode, self.matrix, w.HBox([self.from_arm, self.solve_button, self.progress]),
            self.answers_html, w.HBox([self.choice, self.show_button, self.send_button]), self.message])
        self._from_arm()

    def target(self) -> np.ndarray:
        """The target pose ``(4, 4)`` [m] as typed."""
        if self.mode.value == "typed matrix":
            return parse_pose_matrix(self.matrix.value)
        values = [f.value for f in self.fields]
        return target_pose(values[:3], values[3:])

    def set_target(self, T: np.ndarray) -> None:
        """Fill the target's fields (both forms) with the pose ``T (4, 4)`` [m]."""
        values = [*(T[:3, 3] * 1e3), *np.degrees(matrix_to_rpy(T[:3, :3]))]
        for field, value in zip(self.fields, values):
            field.value = round(float(value), 6)
        self.matrix.value = "\n".join(" ".join(f"{v + 0.0:.6g}" for v in [*T[i, :3], T[i, 3] * 1e3]) for i in range(3))

    @shows_errors
    def _from_arm(self, _=None) -> None:
        self.set_target(fk(self.panel.robot, self.panel.fk.q))
        self.mode.value = "position and roll-pitch-yaw"
        self.solve()

    @shows_errors
    def _nudge(self, k: int, sign: int, _=None) -> None:
        self.mode.value = "position and roll-pitch-yaw"
        step = self.step_mm.value if k < 3 else self.step_deg.value
        self.fields[k].value = round(self.fields[k].value + sign * step, 6)
        self.solve()

    @shows_errors
    def solve(self) -> None:
        """Answer the typed target by every method and list the answers."""
        panel = self.panel
        self.answers, self.answers_html.value, self.choice.options = [], "", []   # a failed solve shows none
        T = self.target()
        self.progress.layout.visibility = "visible"
        self.progress.value = 0

        def step(done: int, total: int) -> None:
            self.progress.max, self.progress.value = total, done

        try:
            self.answers = ik_answers(panel.robot, T, learned=panel.models.ik, learned_note=panel.models.ik_note,
                                      seed=panel.seed, progress=step)
        finally:
            self.progress.layout.visibility = "hidden"
        n = panel.robot.n
        rows = []
        for k, a in enumerate(self.answers):
            angles = ["–"] * n if a.q is None else [f"{round(v, 2) + 0.0:.2f}" for v in np.degrees(a.q)]
            errors = ["–", "–"] if a.q is None else [_small(a.pos_error_m * 1e3), _small(np.degrees(a.rot_error_rad))]
            time_ms = "–" if np.isnan(a.seconds) else f"{a.seconds * 1e3:.3g}"
            if k and a.method.startswith("closed form") and self.answers[k - 1].method.startswith("closed form"):
                time_ms = "(same)"      # the closed form answers every branch in one solve
            verdict = "yes" if a.reaches else "no"
            rows.append([html.escape(a.method), *angles, *errors, time_ms, verdict,
                         _line(a.note, _NOTE)])
        names = [f"{j} [deg]" for j in panel.robot.joint_names]
        self.answers_html.value = _table(["method", *names, "position error [mm]", "orientation error [deg]",
                                          "time [ms]", "reaches", "note"], rows)
        usable = [(a.method, i) for i, a in enumerate(self.answers) if a.q is not None]
        best = next((i for _, i in usable if self.answers[i].reaches), usable[0][1] if usable else None)
        self.choice.options = usable
        if best is not None:
            self.choice.value = best

    def _chosen(self) -> np.ndarray:
        if self.choice.value is None:
            raise PanelInputError("answer: solve a target first; no answer to take")
        return self.answers[self.choice.value].q

    @shows_errors
    def _show(self, _=None) -> None:
        self.panel.fk.set_q(self._chosen())

    @shows_errors
    def _send(self, _=None) -> None:
        self.panel.trajectory.set_final(self._chosen())
        self.panel.select(self.panel.trajectory)


class TrajectoryPage:
    """A joint trajectory between two configurations (the dissertation's cubic, or a quintic): the
    boundary values per joint, start, step and end time; its positions, velocities and
    accelerations plotted; the arm animated along it with the tool's path; a rerun recording."""

    title = "Trajectory"

    def __init__(self, panel: "ArmPanel"):
        self.panel = panel
        robot = panel.robot
        self.message = w.HTML()
        self.notes = w.HTML()
        cell = dict(layout=w.Layout(width="110px"))
        self.q0, self.qf, self.v0, self.vf = ([w.FloatText(value=0.0, **cell) for _ in range(robot.n)]
                                              for _ in range(4))
        grid = [w.HTML("<b>joint</b>"), w.HTML("<b>initial [deg]</b>"), w.HTML("<b>final [deg]</b>"),
                w.HTML("<b>initial [deg/s]</b>"), w.HTML("<b>final [deg/s]</b>")]
        for j, name in enumerate(robot.joint_names):
            grid += [w.HTML(html.escape(name)), self.q0[j], self.qf[j], self.v0[j], self.vf[j]]
        self.grid = w.GridBox(grid, layout=w.Layout(grid_template_columns="repeat(5, 115px)"))
        self.t0 = w.FloatText(value=0.0, description="start [s]", **cell, style={"description_width": "60px"})
        self.dt = w.FloatText(value=0.2, description="step [s]", **cell, style={"description_width": "60px"})
        self.tf = w.FloatText(value=6.0, description="end [s]", **cell, style={"description_width": "60px"})
        for box in (self.t0, self.dt, self.tf):
            box.layout.width = "160px"
        self.profile = w.Dropdown(options=list(PROFILES), value="cubic", description="profile",
                                  layout=w.Layout(width="200px"))
        buttons = {"initial ← arm": lambda _: self._from_arm(self.q0), "final ← arm": lambda _: self._from_arm(self.qf),
                   "compute": lambda _: self.compute()}
        self.buttons = {}
        for label, action in buttons.items():
            self.buttons[label] = w.Button(description=label, button_style="primary" if label == "compute" else "")
            self.buttons[label].on_click(action)
        self.save_button = w.Button(description="save as rerun recording", layout=w.Layout(width="auto"))
        self.save_button.on_click(self._save)
        self.fig, self.canvas = _figure(6.2, 5.6)
        self.axes = self.fig.subplots(3, 1, sharex=True)
        self.view = _ArmView(robot, panel.fk.q, size=(4.6, 4.4), with_path=True)
        self.play = w.Play(min=0, max=0, step=1, interval=200, description="play")
        self.frame = w.IntSlider(min=0, max=0, description="sample", continuous_update=True)
        w.jslink((self.play, "value"), (self.frame, "value"))
        self.frame.observe(self._frame, names="value")
        self.trajectory = None
        self.tip = None
        controls = w.VBox([self.grid, w.HBox([self.t0, self.dt, self.tf, self.profile]),
                           w.HBox(list(self.buttons.values()) + [self.save_button]), self.notes, self.message])
        self.widget = w.VBox([controls, w.HBox([self.canvas, w.VBox([self.view.canvas,
                                                                     w.HBox([self.play, self.frame])])])])
        self._from_arm(self.q0)
        # Until an answer is sent here: a quarter of each joint's range above its middle.
        self._set(self.qf, robot.qlim.mean(axis=1) + 0.25 * np.ptp(robot.qlim, axis=1))

    def _set(self, boxes, q) -> None:
        for box, value in zip(boxes, np.degrees(np.asarray(q, dtype=float))):
            box.value = round(float(value), 6)

    def set_final(self, q) -> None:
        """Take ``q (n,)`` [rad] as the final position and recompute."""
        self._set(self.qf, q)
        self.compute()

    @shows_errors
    def _from_arm(self, boxes) -> None:
        self._set(boxes, self.panel.fk.q)

    @shows_errors
    def compute(self) -> None:
        """Make the trajectory from the typed values, plot it, ready the animation and update
        the dynamics page."""
        robot = self.panel.robot
        self.clear()            # a failed compute leaves nothing of the last trajectory, nor its torques
        values = [[b.value for b in boxes] for boxes in (self.q0, self.qf, self.v0, self.vf)]
        trajectory, notes = joint_trajectory(robot, *values, t0=self.t0.value, dt=self.dt.value, tf=self.tf.value,
                                             profile=self.profile.value, max_samples=self.panel.max_samples)
        self.trajectory = trajectory
        self.notes.value = "<br>".join(_line(n, _NOTE) for n in notes)
        t = trajectory.t
        for ax, (data, label) in zip(self.axes, ((trajectory.q, "position [deg]"),
                                                 (trajectory.qd, "velocity [deg/s]"),
                                                 (trajectory.qdd, "acceleration [deg/s²]"))):
            ax.clear()
            for j, name in enumerate(robot.joint_names):
                ax.plot(t, np.degrees(data[:, j]), color=f"C{j}", label=name)
            ax.set_ylabel(label, fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
        self.axes[-1].set_xlabel("t [s]", fontsize=8)
        self.axes[0].legend(fontsize=7, ncols=min(robot.n, 6), loc="lower left", bbox_to_anchor=(0, 1.02))
        self.canvas.draw_idle()
        self.tip = fk(robot, trajectory.q)[:, :3, 3]
        self.view.show_path(self.tip)
        self.play.interval = int(max(20, round(1e3 * float(np.median(np.diff(t))))))
        self.frame.max = self.play.max = len(t) - 1
        if self.frame.value == 0:
            self._frame()
        else:
            self.frame.value = 0
        self.panel.dynamics.compute()

    def clear(self) -> None:
        """Forget the trajectory: no plots, path, animation, notes or torques (the dynamics page
        cleared too), until the next computation."""
        self.trajectory = self.tip = None
        self.notes.value = ""
        for ax in self.axes:
            ax.clear()
        self.canvas.draw_idle()
        self.view.show_path(None)
        self.view.update()
        self.frame.value = 0
        self.frame.max = self.play.max = 0
        self.panel.dynamics.clear()

    def _frame(self, change=None) -> None:
        if self.trajectory is None:
            return
        k = min(self.frame.value, len(self.trajectory.t) - 1)
        self.view.show(self.trajectory.q[k], travelled=self.tip[:k + 1])

    @shows_errors
    def _save(self, _=None) -> None:
        if self.trajectory is None:
            raise PanelInputError("recording: compute a trajectory first")
        dynamics = self.panel.dynamics
        parts = dynamics.parts if dynamics.trajectory is self.trajectory else None
        if not is_robot_name(self.panel.robot.name):      # it names the file: nothing outside the directory
            raise PanelInputError(f"recording: the robot's name {self.panel.robot.name!r} cannot name a file "
                                  f"(letters, digits, '_', '-' or '.', no '..')")
        path = self.panel.recordings_dir / f"{self.panel.robot.name}-panel-trajectory.rrd"
        try:
            record_trajectory(self.panel.robot, self.trajectory, path, tau=None if parts is None else parts.total,
                              name=f"{self.panel.robot.name} panel trajectory",
                              max_bytes=self.panel.max_recording_bytes)
        except RecordingTooLarge as error:
            raise PanelInputError(f"recording: {error}") from None
        self.message.value = _line(f"saved {shown_path(path)} (open it with: rerun {shown_path(path)})")


class DynamicsPage:
    """Inverse dynamics: the Newton–Euler joint torques along the trajectory page's trajectory,
    split into inertial ``M(q) q̈``, Coriolis ``C(q, q̇) q̇`` and gravity ``g(q)`` parts, with the
    learned model's torques beside them and each joint's drive limit where the robot file gives
    one."""

    title = "Inverse dynamics"

    def __init__(self, panel: "ArmPanel"):
        self.panel = panel
        robot = panel.robot
        self.message = w.HTML()
        self.notes = w.HTML()
        self.progress = w.IntProgress(min=0, max=1, layout=w.Layout(width="300px", visibility="hidden"))
        self.peaks = w.HTML()
        rows = -(-robot.n // 2)
        self.fig, self.canvas = _figure(9.0, 1.7 * rows + 0.9)
        grid = self.fig.subplots(rows, 2, sharex=True, squeeze=False)
        self.axes = grid.T.ravel()[:robot.n]           # joints down the first column, then the second
        for ax in grid.T.ravel()[robot.n:]:
            ax.set_visible(False)
        self.parts = self.trajectory = None
        self.widget = w.VBox([self.progress, self.notes, self.peaks, self.message, self.canvas])

    def clear(self) -> None:
        """Forget the torques: no plots, peaks or notes until the next computation."""
        self.parts = self.trajectory = None
        self.notes.value = self.peaks.value = ""
        for ax in self.axes:
            ax.clear()
        self.fig.legends.clear()
        self.canvas.draw_idle()

    @shows_errors
    def compute(self) -> None:
        """Torques of the trajectory page's trajectory, with progress."""
        panel = self.panel
        robot = panel.robot
        trajectory = panel.trajectory.trajectory
        self.clear()
        if trajectory is None:
            raise PanelInputError("torques: compute a trajectory on the trajectory page first")
        self.progress.layout.visibility = "visible"

        def step(done: int, total: int) -> None:
            self.progress.max, self.progress.value = total, done

        try:
            parts = torque_parts(robot, trajectory, learned=panel.models.id, progress=step)
        finally:
            self.progress.layout.visibility = "hidden"
        self.parts, self.trajectory = parts, trajectory
        notes = [panel.models.id_note if panel.models.id is None else "", parts.note]
        self.notes.value = "<br>".join(_line(n, _NOTE) for n in notes if n)
        t = trajectory.t
        series = [(parts.total, "total (Newton–Euler)", dict(color="0.25", lw=4, alpha=0.45)),
                  (parts.inertial, "inertial M(q) q̈", dict(color="C0", lw=1.2)),
                  (parts.coriolis, "Coriolis C(q, q̇) q̇", dict(color="C2", lw=1.2)),
                  (parts.gravity, "gravity g(q)", dict(color="C1", lw=1.2))]
        if parts.learned is not None:
            series.append((parts.learned, "learned ID (chapter 6)", dict(color="C3", lw=1.5, ls="--")))
        rows = []
        for j, ax in enumerate(self.axes):
            ax.clear()
            for values, label, style in series:
                ax.plot(t, values[:, j], label=label, **style)
            limit = robot.effort[j]
            if np.isfinite(limit):
                for sign in (-1, 1):
                    ax.axhline(sign * limit, color="C3", lw=0.8, ls=":",
                               label="drive limit" if sign > 0 else None)
            ax.set_ylabel(f"{robot.joint_names[j]} [N·m]", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
            peak = float(np.abs(parts.total[:, j]).max())
            rows.append([html.escape(robot.joint_names[j]), f"{peak:.3g}",
                         f"{limit:.3g}" if np.isfinite(limit) else "not given",
                         f"{peak / limit:.0%}" if np.isfinite(limit) else "–"])
        for ax in (self.axes[-1], self.axes[(len(self.axes) - 1) // 2]):
            ax.set_xlabel("t [s]", fontsize=8)
            ax.xaxis.set_tick_params(labelbottom=True)
        handles, labels = self.axes[0].get_legend_handles_labels()
        for ax in self.axes[1:]:
            for h, label in zip(*ax.get_legend_handles_labels()):
                if label not in labels:
                    handles.append(h)
                    labels.append(label)
        self.fig.legends.clear()
        self.fig.legend(handles, labels, loc="outside upper center", ncols=3, fontsize=7)
        self.peaks.value = _table(["joint", "peak |τ| [N·m]", "drive limit [N·m]", "peak / limit"], rows)
        self.canvas.draw_idle()


# --------------------------------------------------------------------------------------------
# The panel


class ArmPanel:
    """The four pages for one robot.

    Args:
        robot: a :class:`~nfarm.model.robot.Robot`, or a robot file (or a shipped robot's name,
            :func:`nfarm.publishing.panel_compute.shipped_robots`).
        models_dir: where chapter 06's models are (default ``build/models/<robot name>/``).
        recordings_dir: where "save as rerun recording" writes (default ``build/panel/``).
        near_singular: the singularity warning's threshold (:func:`~nfarm.publishing.panel_compute.pose_readout`).
        seed: the seed of Levenberg–Marquardt's starting guesses and restarts.
        max_samples: the most samples of a trajectory
            (:func:`~nfarm.publishing.panel_compute.joint_trajectory`: at 100 000 every page
            action takes 1-2.5 s).
        max_recording_bytes: the largest "save as rerun recording" (checked before writing;
            100 000 samples of a 6-joint arm with its torques take about 75 MiB).
    """

    def __init__(self, robot: Robot | str | Path, *, models_dir: str | Path | None = None,
                 recordings_dir: str | Path | None = None, near_singular: float = 0.02, seed: int = 0,
                 max_samples: int = 100_000, max_recording_bytes: int = 128 * 2**20):
        self.load_notes: list[str] = []
        if not isinstance(robot, Robot):
            robots = shipped_robots()
            path = robots.get(str(robot), robot)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                robot = load_robot(path)
            self.load_notes = [str(c.message).splitlines()[0] for c in caught]
        self.robot = robot
        self.near_singular = near_singular
        self.seed = seed
        self.max_samples, self.max_recording_bytes = max_samples, max_recording_bytes
        self.recordings_dir = Path(recordings_dir) if recordings_dir else BUILD / "panel"
        self.models = trained_models(robot, Path(models_dir) if models_dir else None)
        self.fk = FKPage(self)
        self.ik = IKPage(self)
        self.dynamics = DynamicsPage(self)
        self.trajectory = TrajectoryPage(self)
        self.trajectory.compute()
        self.pages = [self.fk, self.ik, self.trajectory, self.dynamics]
        self.tabs = w.Tab(children=[p.widget for p in self.pages], titles=[p.title for p in self.pages])
        notes = "".join(f"<div>{_line(n, _NOTE)}</div>" for n in self.load_notes)
        self.widget = w.VBox([w.HTML(notes), self.tabs])

    def select(self, page) -> None:
        """Show ``page`` (one of :attr:`pages`)."""
        self.tabs.selected_index = self.pages.index(page)


class Panel:
    """The arm panel with a robot chooser: every robot file in ``params/robots/``; choosing
    another builds its :class:`ArmPanel` (keyword arguments are passed on)."""

    def __init__(self, robot: str = "intelbot5", **options):
        robots = shipped_robots()
        if robot not in robots:
            raise ValueError(f"robot: one of {', '.join(robots)}, got "
                             f"{repr(str(robot)) if isinstance(robot, str) else type(robot).__name__}")
        self.options = options
        self.chooser = w.Dropdown(options=list(robots), value=robot, description="robot")
        self.message = w.HTML()
        self.arm = ArmPanel(robot, **options)
        self.body = w.VBox([self.arm.widget])
        self.chooser.observe(self._choose, names="value")
        self.widget = w.VBox([w.HBox([self.chooser, self.message]), self.body])

    @shows_errors
    def _choose(self, change) -> None:
        self.message.value = _line(f"loading {change['new']} …")
        self.arm = ArmPanel(change["new"], **self.options)
        self.body.children = [self.arm.widget]
        self.message.value = ""
