"""Figures of the study, saved byte-reproducibly.

:func:`save_figure` fixes everything that would make two runs differ: the DPI and the PNG
metadata (no software version, no timestamp); PNGs are always rendered by Agg, whatever
backend shows the figure. Each plotting function returns a
:class:`matplotlib.figure.Figure` and leaves saving to the caller.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import matplotlib.ticker as mticker
import numpy as np
from matplotlib.figure import Figure

from ..infra.paths import atomic_path
from ..model.kinematics import fk, fk_all
from ..model.robot import Robot
from .numbering import anchor, number

__all__ = ["save_figure", "draw_arm", "plot_arm_poses", "plot_workspace", "plot_map",
           "plot_region", "plot_histograms", "plot_id_trajectories", "plot_torque_distributions",
           "plot_convergence", "plot_joint_paths", "plot_profiles", "plot_per_joint",
           "plot_motion", "plot_learning_curves", "plot_joint_curves", "plot_size_curve", "plot_error_by_size",
           "plot_predicted_vs_true", "plot_sweep", "plot_error_map", "plot_error_against",
           "plot_planar_subproblem", "plot_against", "DPI"]

#: Resolution of every saved figure.
DPI = 110


def save_figure(fig: Figure, out_dir: str | os.PathLike, name: str, caption: str = "", *,
                show: bool | None = None) -> str:
    """Write ``fig`` to ``out_dir/name.png`` atomically and reproducibly; return the path.

    ``caption`` is stored in the PNG (its ``Description`` text chunk); the report's index
    shows it under the figure. ``show`` (default: when an IPython kernel runs this, as in a
    chapter) displays the saved PNG with the caption under it — visible, and as the image's
    alternative text — and closes ``fig``: the page shows what was published, captioned, once
    (a ``plt.show()`` after it shows nothing)."""
    path = os.path.join(out_dir, f"{name}.png")
    metadata = {"Software": None, **({"Description": caption} if caption else {})}
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI, metadata=metadata)
    if show if show is not None else _in_kernel():
        _display_figure(path, caption)
        plt.close(fig)
    return path


def _in_kernel() -> bool:
    """Whether this runs in an IPython kernel (a notebook), not a script or a terminal."""
    try:
        from IPython import get_ipython
    except ImportError:             # pragma: no cover — IPython comes with the project
        return False
    return getattr(get_ipython(), "kernel", None) is not None


def figure_number(path: str) -> str:
    """"Figure 6.3." for the third figure a chapter shows (its file named ``06_…``), in the order
    they are first shown in this process (:func:`nfarm.presentation.numbering.number`); a figure
    shown again keeps its number; "Figure." for a file not named after a chapter."""
    found = number("Figure", os.path.splitext(os.path.basename(path))[0])
    return f"Figure {found}." if found else "Figure."


def _display_figure(path: str, caption: str) -> None:
    """A saved figure as a notebook output: HTML (the image, its alternative text and a visible
    caption) for pages and JupyterLab, the PNG itself for other front ends."""
    import base64
    import html

    from IPython.display import display

    with open(path, "rb") as f:
        data = base64.b64encode(f.read()).decode("ascii")
    text = html.escape(caption or os.path.basename(path), quote=True)
    name = html.escape(anchor("Figure", os.path.splitext(os.path.basename(path))[0]), quote=True)  # citations link here
    figure = (f'<figure class="nfarm-figure" id="{name}" style="margin:.5em 0 1.5em">'
              f'<img src="data:image/png;base64,{data}" alt="{text}" style="max-width:100%">'
              f'<figcaption style="color:#444;font-size:.9em;margin-top:.3em"><b>{figure_number(path)}</b> {text}'
              f'</figcaption></figure>')
    display({"text/html": figure, "image/png": data, "text/plain": f"Figure: {caption}"}, raw=True)


def draw_arm(ax, robot: Robot, q: np.ndarray, *, color: str = "C0", label: str | None = None,
             frame_scale: float = 0.04) -> None:
    """Draw the arm at ``q (n,)`` on a 3-D axes: links through the DH frame origins, the joints
    as dots, and the tool frame as a red-green-blue triad (x, y, z)."""
    frames = fk_all(robot, q)
    T_0e = fk(robot, q)
    points = np.vstack([frames[:, :3, 3], T_0e[:3, 3]])
    ax.plot(*points.T, "-", color=color, lw=3, label=label, solid_capstyle="round")
    ax.plot(*frames[:, :3, 3].T, "o", color="k", ms=4)
    for axis, axis_color in zip(T_0e[:3, :3].T, ("r", "g", "b")):
        tip = T_0e[:3, 3] + frame_scale * axis
        ax.plot(*np.column_stack([T_0e[:3, 3], tip]), color=axis_color, lw=1.5)


def _equal_3d(ax, points: np.ndarray) -> None:
    center = (points.max(axis=0) + points.min(axis=0)) / 2
    half = (points.max(axis=0) - points.min(axis=0)).max() / 2 * 1.1
    ax.set(xlim=(center[0] - half, center[0] + half), ylim=(center[1] - half, center[1] + half),
           zlim=(max(center[2] - half, points[:, 2].min() - 0.02), center[2] + half))
    ax.set_box_aspect((1, 1, 1))


def plot_arm_poses(robot: Robot, poses: Mapping[str, np.ndarray]) -> Figure:
    """One 3-D panel per named configuration ``q (n,)`` [rad]; a legend explains the tool
    frame's colours."""
    fig = plt.figure(figsize=(3.9 * len(poses), 4.4), layout="constrained")
    reach = np.vstack([np.vstack([fk_all(robot, q)[:, :3, 3], fk(robot, q)[:3, 3]])
                       for q in poses.values()])
    for k, (name, q) in enumerate(poses.items()):
        ax = fig.add_subplot(1, len(poses), k + 1, projection="3d")
        draw_arm(ax, robot, np.asarray(q), color=f"C{k}")
        _equal_3d(ax, np.vstack([reach, [[0, 0, 0]]]))
        ax.set_box_aspect((1, 1, 1), zoom=0.82)       # room for every axis label
        ax.set_title(name, fontsize=10, y=0.93)   # within the axes: the layout does not see 3-D titles
        ax.set_xlabel("x [m]", fontsize=9)
        ax.set_ylabel("y [m]", fontsize=9)
        ax.set_zlabel("z [m]", fontsize=9)
        ax.tick_params(labelsize=8)
        for axis in (ax.xaxis, ax.yaxis, ax.zaxis):     # four ticks an axis: their labels do not run together
            axis.set_major_locator(mticker.MaxNLocator(4))
        ax.view_init(elev=20, azim=-60)
    handles = [plt.Line2D([], [], color=c, lw=1.5, label=f"tool {a} axis")
               for c, a in zip(("r", "g", "b"), "xyz")]
    handles.append(plt.Line2D([], [], color="k", marker="o", ls="", ms=4, label="joint (DH frame origin)"))
    fig.legend(handles=handles, loc="outside lower center", ncols=4, fontsize=9)
    return fig


def plot_planar_subproblem(robot: Robot, solutions: Mapping[str, np.ndarray]) -> Figure:
    """The closed form's planar sub-problem (:mod:`nfarm.solvers.geometric_ik`) in the arm's plane:
    for each named configuration ``q (5,)`` [rad] (solutions of one pose), the links from the
    shoulder axis through the elbow to the wrist-pitch axis and the wrist point, the elbow
    angle γ, and the roll axis through the wrist point; angles in degrees. Up in the picture
    is up in the world (against gravity)."""
    from ..solvers.geometric_ik import planar_points
    fig, ax = plt.subplots(figsize=(7.2, 5.6), layout="constrained")
    points = []
    for k, (name, q) in enumerate(solutions.items()):
        p = planar_points(robot, np.asarray(q))
        chain = np.array([p["shoulder"], p["elbow"], p["wrist pitch"], p["wrist point"]])
        points.append(chain)
        ax.plot(*chain.T, "-o" if k == 0 else "--o", color=f"C{k}", lw=3 if k == 0 else 2, ms=6,
                label=f"{name}: θ̄2 = {np.degrees(p['theta2']):.1f}°, γ = "
                      f"{np.degrees(p['gamma']):.1f}°")
    first = planar_points(robot, np.asarray(next(iter(solutions.values()))))
    wrist, axis = first["wrist point"], first["roll axis"]
    span = np.vstack(points)
    size = float(np.ptp(span, axis=0).max())
    ax.plot(*np.column_stack([wrist - 0.3 * size * axis, wrist + 0.3 * size * axis]), ":",
            color="0.3", lw=1.5, label="roll axis (joint 5), direction Φ")
    ax.annotate("", xy=first["wrist pitch"], xytext=(0, 0),
                arrowprops=dict(arrowstyle="->", color="0.5", lw=1.2))
    ax.text(*(0.5 * first["wrist pitch"]), "  Q", color="0.35", fontsize=11)
    for label, key in (("shoulder (joint 2)", "shoulder"), ("elbow (joint 3)", "elbow"),
                       ("wrist pitch (joint 4)", "wrist pitch")):
        ax.annotate(label, first[key], xytext=(6, -14), textcoords="offset points", fontsize=9,
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8))
    ax.axvline(first["base axis x"], color="k", lw=0.8, ls="-.", label="base axis (joint 1)")
    ax.set(xlabel="x₁ [m] (frame 1)", ylabel="y₁ [m] (frame 1)" if first["y1 up"] else
           "y₁ [m] (frame 1, pointing down: drawn reversed so that up is up)",
           aspect="equal", title="The arm's plane: two links reach the point Q")
    if not first["y1 up"]:
        ax.invert_yaxis()
    ax.grid(alpha=0.3)
    # Below the axes: inside, "best" put it over the roll axis's far end
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.11), ncols=2, fontsize=8.5, frameon=False)
    return fig


def plot_workspace(points: np.ndarray, *, title: str = "") -> Figure:
    """Side (x–z) and top (x–y) views of a cloud of tool positions ``(N, 3)`` [m]."""
    fig, (side, top) = plt.subplots(1, 2, figsize=(9, 4.2), layout="constrained")
    style = dict(s=0.4, alpha=0.25, c="C0", linewidths=0, rasterized=True)
    side.scatter(points[:, 0], points[:, 2], **style)
    side.set(xlabel="x [m]", ylabel="z [m]", title="side view (x–z)", aspect="equal")
    top.scatter(points[:, 0], points[:, 1], **style)
    top.set(xlabel="x [m]", ylabel="y [m]", title="top view (x–y)", aspect="equal")
    for ax in (side, top):
        ax.plot(0, 0, "k+", ms=10)
        ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    return fig


def plot_map(ax, x_edges: np.ndarray, y_edges: np.ndarray, values: np.ndarray, *,
             label: str, singular_level: float | None = None, cmap: str = "viridis"):
    """A colour map of ``values (len(x_edges) − 1, len(y_edges) − 1)`` (NaN: no data) with an
    optional contour at ``singular_level`` marking the near-singular region."""
    mesh = ax.pcolormesh(x_edges, y_edges, values.T, cmap=cmap, shading="flat")
    ax.figure.colorbar(mesh, ax=ax, label=label, shrink=0.85)
    if singular_level is not None:
        xc = (x_edges[:-1] + x_edges[1:]) / 2
        yc = (y_edges[:-1] + y_edges[1:]) / 2
        filled = np.where(np.isnan(values), np.inf, values)
        ax.contour(xc, yc, filled.T, levels=[singular_level], colors="r", linewidths=1.2)
    return mesh


def plot_convergence(histories: Mapping[str, Mapping[str, np.ndarray]], *, floor: float = 1e-16) -> Figure:
    """Error against iteration: one row per case, position and orientation side by side.

    ``histories[case][label]`` is a ``(K, 2)`` history from ``solve(..., record_history=True)``
    (position [m], orientation [rad]); errors are drawn on a log scale, clipped at ``floor``.
    Each method has its own colour, line style and marker, so that curves lying on top of
    each other stay visible; one legend for the figure.
    """
    fig, axes = plt.subplots(len(histories), 2, figsize=(11, 3.3 * len(histories)),
                             layout="constrained", squeeze=False)
    styles = [("-", "o"), ("--", "s"), (":", "^"), ("-.", "v"), ((0, (5, 2, 1, 2)), "D"), ("-", "x")]
    labels = {}
    for row, (case, curves) in zip(axes, histories.items()):
        for k, (label, history) in enumerate(curves.items()):
            steps = np.arange(len(history))
            line, marker = styles[k % len(styles)]
            for ax, column in zip(row, (0, 1)):
                (handle,) = ax.semilogy(steps, np.maximum(history[:, column], floor), ls=line,
                                        marker=marker, markevery=max(len(steps) // 12, 1),
                                        ms=4, color=f"C{k}", lw=1.6 - 0.2 * k, label=label)
                labels.setdefault(label, handle)
        for ax, what in zip(row, ("position error [m]", "orientation error [rad]")):
            ax.axhline(1e-9, color="k", lw=0.8, ls=":")
            ax.set(xlabel="iteration", ylabel=what, title=case)
            ax.grid(alpha=0.3, which="both")
    fig.legend(labels.values(), labels.keys(), loc="outside lower center",
               ncols=min(len(labels), 3), fontsize=9)
    return fig


def plot_joint_paths(s: np.ndarray, paths: Mapping[str, np.ndarray], joint_names, *,
                     floor: float = 1e-3) -> Figure:
    """Joint angles [deg] along a path parameter ``s (K,)``: one panel per joint, one line per
    named solution ``(K, n)`` [rad].

    A joint that every solution holds within ``floor`` [deg] along the path is drawn on a ±1°
    axis and titled "constant": autoscaled, its panel would magnify the solver's rounding
    (10⁻⁷°) into spikes that look like motion.

    The first solution is drawn as a wide pale band and the others as points on thin lines over
    it, so that solutions that coincide stay visible: the points on the band."""
    n = len(joint_names)
    fig, axes = plt.subplots(1, n, figsize=(2.6 * n, 3.0), layout="constrained", sharex=True)
    for k, (label, q) in enumerate(paths.items()):
        for j, ax in enumerate(axes):
            if k == 0:
                ax.plot(s, np.degrees(q[:, j]), "-", color="C0", label=label, lw=6, alpha=0.35,
                        solid_capstyle="butt")
            else:
                ax.plot(s, np.degrees(q[:, j]), ".-", color=f"C{k}", label=label, ms=3, lw=0.8, zorder=2 + k)
    for j, (ax, name) in enumerate(zip(axes, joint_names)):
        values = np.concatenate([np.degrees(np.asarray(q)[:, j]) for q in paths.values()])
        held = np.ptp(values) < floor
        if held:
            middle = float(np.round(values.mean(), 3)) + 0.0        # (+ 0.0: no "-0")
            ax.set_ylim(middle - 1, middle + 1)
        ax.set(title=f"{name} (constant)" if held else name, xlabel="path parameter s")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("joint angle [deg]")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=len(labels), fontsize=9)
    return fig


def plot_profiles(t: np.ndarray, profiles: Mapping[str, np.ndarray], joint_names) -> Figure:
    """One panel per named profile ``(K, n)`` against time ``t (K,)``, one line per joint
    (angles are shown in degrees: pass values in radians)."""
    fig, axes = plt.subplots(1, len(profiles), figsize=(4.2 * len(profiles), 3.4),
                             layout="constrained", squeeze=False)
    dashes = ["-", "--", "-.", ":", (0, (5, 1, 1, 1, 1, 1)), (0, (8, 2))]
    widths = np.linspace(4.0, 1.2, len(joint_names))   # narrower on top: coinciding joints stay visible
    for ax, (label, values) in zip(axes[0], profiles.items()):
        for j, name in enumerate(joint_names):      # own dashes and width
            ax.plot(t, np.degrees(values[:, j]), ls=dashes[j % len(dashes)], marker=".", ms=3,
                    lw=widths[j], alpha=0.55 if j == 0 else 0.9, label=name, zorder=2 + j)
        ax.set(xlabel="t [s]", ylabel=label, title=label.split(" [")[0])
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    return fig


def plot_per_joint(t: np.ndarray, series: Mapping[str, np.ndarray], joint_names, *,
                   ylabel: str, focus: float | None = None) -> Figure:
    """One panel per joint, one line per named series ``(K, n)`` against time ``t (K,)``; the
    legend below the panels, where it hides no data.

    ``focus``: each panel's y range is the first series' (the reference's) range widened
    ``focus`` times about its middle, so that a prediction far off does not flatten the others;
    a series that leaves a panel's range is named so in the legend.

    The reference is a wide pale band, the others narrower the later they come, each with its
    own dashes and drawn over the ones before: a series that coincides with another stays
    visible."""
    n = len(joint_names)
    fig, axes = plt.subplots(1, n, figsize=(2.9 * n, 3.3), layout="constrained", sharex=True)
    axes = np.atleast_1d(axes)
    dashes = ["--", "-.", ":", (0, (5, 1, 1, 1)), (0, (8, 2))]
    for k, (label, values) in enumerate(series.items()):
        style = dict(lw=5, alpha=0.35, ls="-", solid_capstyle="butt") if k == 0 else \
            dict(lw=max(2.6 - 0.5 * (k - 1), 1.0), ls=dashes[(k - 1) % len(dashes)])
        for j, ax in enumerate(axes):
            ax.plot(t, values[:, j], color=f"C{k}", label=label, zorder=2 + k, **style)
    leaves = set()
    if focus is not None:
        reference = np.asarray(next(iter(series.values())))
        for j, ax in enumerate(axes):
            lo, hi = float(reference[:, j].min()), float(reference[:, j].max())
            middle = (lo + hi) / 2
            half = focus * max((hi - lo) / 2, 1e-3 * max(abs(lo), abs(hi)), 1e-12)
            ax.set_ylim(middle - half, middle + half)
            leaves |= {label for label, values in series.items()
                       if np.any(np.abs(np.asarray(values)[:, j] - middle) > half)}
    for ax, name in zip(axes, joint_names):
        ax.set(title=name, xlabel="t [s]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(ylabel)
    handles, labels = axes[0].get_legend_handles_labels()
    labels = [f"{label} (leaves the axes)" if label in leaves else label for label in labels]
    fig.legend(handles, labels, loc="outside lower center", ncol=min(len(labels), 3), fontsize=8,
               frameon=False)
    return fig


def plot_motion(robot: Robot, q: np.ndarray, *, frames: int = 5, t: np.ndarray | None = None,
                title: str = "") -> Figure:
    """The arm at ``frames`` instants of a motion ``q (K, n)`` and the path its tool draws;
    the arms are coloured by time (``t (K,)`` [s], or the sample index), with a colour bar."""
    fig = plt.figure(figsize=(6.4, 5.4), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    tip = fk(robot, q)[:, :3, 3]
    time = np.arange(len(q), dtype=float) if t is None else np.asarray(t, dtype=float)
    norm = plt.Normalize(time[0], time[-1])
    for index in np.linspace(0, len(q) - 1, frames).round().astype(int):
        draw_arm(ax, robot, q[index], color=plt.cm.viridis(norm(time[index])))
    ax.plot(*tip.T, color="C1", lw=2, label="tool path")
    points = np.vstack([tip, fk_all(robot, q[:: max(len(q) // 20, 1)])[..., :3, 3].reshape(-1, 3)])
    _equal_3d(ax, np.vstack([points, [[0, 0, 0]]]))
    ax.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]")
    ax.legend(fontsize=8)
    ax.view_init(elev=25, azim=-55)
    bar = fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap="viridis"), ax=ax, shrink=0.6, pad=0.1)
    bar.set_label("t [s]" if t is not None else "sample")
    if title:
        ax.set_title(title)
    return fig


def plot_spread(groups: Mapping[str, Sequence[float]], *, reference: float | None = None,
                reference_label: str = "", ylabel: str = "", title: str = "", log: bool = False) -> Figure:
    """Each group's values as points on one row (a strip plot: every value shown, its mean as a
    bar), with a ``reference`` value as a vertical line; ``ylabel`` names the quantity and unit
    (on the x axis), logarithmic with ``log`` (plain-number ticks). Each row's label names its group
    and how many values it holds; a legend names only the reference line (the rows need none:
    their labels are beside them)."""
    fig, ax = plt.subplots(figsize=(9, 0.8 + 0.5 * len(groups)), layout="constrained")
    for k, values in enumerate(groups.values()):
        values = np.asarray(values, float)
        ax.plot(values, np.full(len(values), k), "o", color=f"C{k}", alpha=0.8)
        ax.plot([values.mean()] * 2, [k - 0.3, k + 0.3], "-", color=f"C{k}", lw=2)
    if reference is not None:
        ax.axvline(reference, color="k", ls="--", lw=1, label=reference_label)
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))      # beside the axes: on no point
    ax.set_yticks(range(len(groups)), [f"{name} ({len(values)})" for name, values in groups.items()], fontsize=8)
    ax.set_ylim(-0.6, len(groups) - 0.4)
    ax.invert_yaxis()
    ax.set_xlabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3, axis="x")
    if log:
        ax.set_xscale("log")
        _readable_log_axis(ax.xaxis)
    return fig


def plot_learning_curves(models: Mapping[str, object]) -> Figure:
    """Training (and validation) RMSE and Jang's step size per epoch, one column per named
    fitted :class:`nfarm.learning.anfis.ANFIS`."""
    fig, axes = plt.subplots(2, len(models), figsize=(4.2 * len(models), 5.2),
                             layout="constrained", squeeze=False, sharex="col")
    for (name, model), (top, bottom) in zip(models.items(), axes.T):
        epochs = np.arange(1, len(model.loss_curve_) + 1)
        top.semilogy(epochs, model.loss_curve_, label="training")
        if model.val_loss_curve_:
            top.semilogy(epochs, model.val_loss_curve_, label="checking")
            top.axvline(model.best_epoch_ + 1, color="k", lw=0.8, ls=":", label="kept")
        top.set(title=name, ylabel="RMSE")
        top.legend(fontsize=8)
        bottom.plot(epochs, model.step_size_curve_, color="C2")
        bottom.set(xlabel="epoch", ylabel="step size k")
        for ax in (top, bottom):
            ax.grid(alpha=0.3, which="both")
    return fig


def plot_region(full: np.ndarray, region: np.ndarray, *, title: str = "") -> Figure:
    """Side (radial distance–height) and top (x–y) views of the tool positions ``(N, 3)`` [m]
    of the full joint ranges (grey) and of a region (colour)."""
    fig, (side, top) = plt.subplots(1, 2, figsize=(10, 4.4), layout="constrained")
    grey = dict(s=0.4, alpha=0.15, c="0.55", linewidths=0, rasterized=True)
    colour = dict(s=0.4, alpha=0.35, c="C1", linewidths=0, rasterized=True)
    for points, style, label in ((full, grey, "full joint ranges"), (region, colour, "IK region")):
        side.scatter(np.hypot(points[:, 0], points[:, 1]), points[:, 2], label=label, **style)
        top.scatter(points[:, 0], points[:, 1], **style)
    side.set(xlabel="distance from the base axis √(x² + y²) [m]", ylabel="z [m]",
             title="side view (every base angle folded in)", aspect="equal")
    top.set(xlabel="x [m]", ylabel="y [m]", title="top view (x–y)", aspect="equal")
    for ax in (side, top):
        ax.plot(0, 0, "k+", ms=10)
        ax.grid(alpha=0.3)
    legend = side.legend(fontsize=8, markerscale=12, loc="upper left")
    for handle in legend.legend_handles:
        handle.set_alpha(1)
    if title:
        fig.suptitle(title)
    return fig


def plot_histograms(columns: Mapping[str, np.ndarray], *, bins: int = 40, ncols: int = 5,
                    reference: Mapping[str, np.ndarray] | None = None,
                    labels: tuple[str, str] = ("data", "reference")) -> Figure:
    """One histogram per named column (the name carries the unit), optionally over a grey
    ``reference`` histogram of the same column; densities, so that sizes may differ."""
    names = list(columns)
    nrows = -(-len(names) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(2.7 * ncols, 2.3 * nrows),
                             layout="constrained", squeeze=False)
    for ax, name in zip(axes.flat, names):
        values = columns[name]
        lo, hi = float(np.min(values)), float(np.max(values))
        if reference is not None:
            lo, hi = min(lo, float(np.min(reference[name]))), max(hi, float(np.max(reference[name])))
            ax.hist(reference[name], bins=bins, range=(lo, hi), density=True, color="0.75",
                    label=labels[1])
        ax.hist(values, bins=bins, range=(lo, hi), density=True, histtype="step", color="C1",
                lw=1.4, label=labels[0])
        ax.set_xlabel(name, fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_yticks([])
    for ax in list(axes.flat)[len(names):]:
        ax.set_visible(False)
    axes[0, 0].set_ylabel("density", fontsize=8)
    if reference is not None:
        axes[0, 0].legend(fontsize=7)
    return fig


def plot_id_trajectories(trajectories: list[Mapping[str, np.ndarray]], joint_names) -> Figure:
    """Position, velocity, acceleration [deg, deg/s, deg/s²] and torque [N·m] over time, one
    row per trajectory (a mapping with ``t, q, qd, qdd, tau``), one line per joint."""
    rows = len(trajectories)
    fig, axes = plt.subplots(rows, 4, figsize=(15, 2.6 * rows), layout="constrained",
                             squeeze=False)
    what = (("q", "q [deg]", True), ("qd", "q̇ [deg/s]", True), ("qdd", "q̈ [deg/s²]", True),
            ("tau", "τ [N·m]", False))
    for r, data in enumerate(trajectories):
        for ax, (key, label, degrees) in zip(axes[r], what):
            values = np.degrees(data[key]) if degrees else data[key]
            for j, name in enumerate(joint_names):
                ax.plot(data["t"], values[:, j], lw=1.1, label=name)
            ax.set(ylabel=label)
            ax.grid(alpha=0.3)
            if r == rows - 1:
                ax.set_xlabel("t [s]")
        axes[r, 0].set_title(f"trajectory {data.get('index', r)}", loc="left", fontsize=9)
    axes[0, 3].legend(fontsize=7, loc="upper right", ncols=2)
    return fig


def plot_torque_distributions(tau: np.ndarray, joint_names) -> Figure:
    """The distribution of each joint's torque ``tau (N, n)`` [N·m] (violins with the median and
    the extremes), one panel per joint on its own axis: the joints' torques differ by orders of
    magnitude, and one shared axis would flatten the small ones to a line."""
    n = len(joint_names)
    fig, axes = plt.subplots(1, n, figsize=(2.0 * n + 1, 3.6), layout="constrained", squeeze=False)
    for j, (ax, name) in enumerate(zip(axes[0], joint_names)):
        parts = ax.violinplot([tau[:, j]], showextrema=True, showmedians=True)
        for body in parts["bodies"]:
            body.set_alpha(0.5)
        ax.set_xticks([1], [name], fontsize=8)
        ax.grid(alpha=0.3, axis="y")
        ax.yaxis.set_major_locator(mticker.MaxNLocator(6))
    axes[0, 0].set_ylabel("τ [N·m]")
    fig.suptitle("joint torques over all training samples (each joint on its own axis)", fontsize=11)
    return fig


def plot_error_by_size(curves, *, unit: str = "%", quantity: str = "worst joint NRMSE",
                       xlabel: str = "training states") -> Figure:
    """Validation error against the number of training states, one line per model (``curves``:
    label → ``(sizes, errors)``, each a sequence), both axes logarithmic, every size a tick;
    models sharing a label's text before ":" (a tier) share a colour, ANFIS solid, others dashed."""
    fig, ax = plt.subplots(figsize=(7.5, 4), layout="constrained")
    groups = list(dict.fromkeys(label.split(":")[0] for label in curves))
    ticks = set()
    for label, (sizes, errors) in curves.items():
        colour = f"C{groups.index(label.split(':')[0]) % 10}"
        ax.plot(sizes, errors, "o-" if "ANFIS" in label else "s--", color=colour, label=label)
        ticks |= {int(round(s)) for s in sizes}
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(f"{quantity} [{unit}]")
    ticks = sorted(ticks)
    ax.set_xticks(ticks, [f"{s:,}" for s in ticks])
    ax.xaxis.set_minor_locator(mticker.NullLocator())
    _readable_log_axis(ax.yaxis)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(alpha=0.3, which="both")
    return fig


def plot_joint_curves(models: list, joint_names, *, joints=None, scale=180 / np.pi,
                      unit: str = "deg", quantity: str = "RMSE", symbol: str = "q",
                      noise=None) -> Figure:
    """Training (solid) and validation (dashed) error per epoch of one fitted ANFIS per joint,
    in ``unit`` (the models' RMSE times ``scale``: a number, or one per joint, e.g. 100 over
    each joint's spread for an NRMSE in %), the kept epoch marked; ``joints``: the indices of
    the joints to show (default all), labelled ``symbol<number> name``; ``noise``: one value
    per joint (in ``unit``), drawn as a dotted line in the joint's colour: the error no model
    can go below (a sensor's noise)."""
    fig, ax = plt.subplots(figsize=(7.5, 4), layout="constrained")
    scales = np.broadcast_to(np.asarray(scale, dtype=float), (len(models),))
    for j in (range(len(models)) if joints is None else joints):
        model, name = models[j], joint_names[j]
        epochs = np.arange(1, len(model.loss_curve_) + 1)
        ax.plot(epochs, np.asarray(model.loss_curve_) * scales[j], color=f"C{j}", lw=1.4,
                label=f"{symbol}{j + 1} {name}")
        if model.val_loss_curve_:
            ax.plot(epochs, np.asarray(model.val_loss_curve_) * scales[j], color=f"C{j}", ls="--", lw=1.2)
            ax.plot(model.best_epoch_ + 1, model.val_loss_curve_[model.best_epoch_] * scales[j], "o",
                    color=f"C{j}", ms=5)
        if noise is not None:
            ax.axhline(float(np.asarray(noise)[j]), color=f"C{j}", ls=":", lw=1.0)
    ax.set_yscale("log")
    ax.set_xlabel("epoch")
    ax.set_ylabel(f"{quantity} [{unit}]")
    epochs = max(len(models[j].loss_curve_) for j in (range(len(models)) if joints is None else joints))
    ax.xaxis.set_major_locator(mticker.MaxNLocator(integer=True, nbins=min(epochs, 10)))
    ax.plot([], [], color="0.3", lw=1.4, label="training")
    ax.plot([], [], color="0.3", ls="--", lw=1.2, label="validation (○ kept epoch)")
    if noise is not None:
        ax.plot([], [], color="0.3", ls=":", lw=1.0, label="sensor noise σ")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(alpha=0.3, which="both")
    _readable_log_axis(ax.yaxis)
    return fig


def plot_size_curve(sizes, errors: np.ndarray, joint_names, *, unit: str = "deg",
                    quantity: str = "validation RMSE", symbol: str = "q",
                    xlabel: str = "training samples", numbers=None, low=None, high=None,
                    spread_label: str = "range over seeds") -> Figure:
    """Validation errors ``errors (len(sizes), n)`` per joint against the training-set size
    (``quantity [unit]`` on the y axis; joints labelled ``symbol<number> name``, ``numbers``
    the joints' 1-based numbers when only some are drawn, default 1..n). With ``low`` and
    ``high`` (arrays like ``errors``) each joint's spread is drawn as a band, named in the
    legend by ``spread_label``."""
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    numbers = range(1, len(joint_names) + 1) if numbers is None else numbers
    for j, (name, number) in enumerate(zip(joint_names, numbers)):
        ax.plot(sizes, errors[:, j], "o-", color=f"C{number - 1}", label=f"{symbol}{number} {name}")
        if low is not None and high is not None:
            ax.fill_between(sizes, np.asarray(low)[:, j], np.asarray(high)[:, j], color=f"C{number - 1}",
                            alpha=0.15, linewidth=0)
    if low is not None and high is not None:
        ax.fill_between([], [], [], color="0.5", alpha=0.3, linewidth=0, label=spread_label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(f"{quantity} [{unit}]")
    sizes = [int(round(s)) for s in sizes]
    ax.set_xticks(sizes, [f"{s:,}" for s in sizes])
    ax.xaxis.set_minor_locator(mticker.NullLocator())
    _readable_log_axis(ax.yaxis)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(alpha=0.3, which="both")
    return fig


def plot_against(x, series: Mapping[str, Sequence[float]], *, xlabel: str, ylabel: str,
                 references: Mapping[str, float] | None = None) -> Figure:
    """Each named series of values against ``x`` (e.g. a validation error against the rule
    count), log-log with ``x``'s values as the ticks; ``references``: named levels drawn as
    dashed lines in the series' colours order (a rival's error, a target). ``xlabel`` and
    ``ylabel`` name quantity and unit."""
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    for k, (name, values) in enumerate(series.items()):
        ax.plot(x, values, "o-", color=f"C{k}", label=name)
    for k, (name, level) in enumerate((references or {}).items()):
        ax.axhline(level, color=f"C{k}", ls="--", lw=1, alpha=0.8, label=name)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ticks = [int(round(v)) for v in x]
    ax.set_xticks(ticks, [f"{t:,}" for t in ticks])
    ax.xaxis.set_minor_locator(mticker.NullLocator())
    _readable_log_axis(ax.yaxis)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(alpha=0.3, which="both")
    return fig


def plot_sweep(labels, metrics: Mapping[str, list], *, title: str = "", max_cells: int = 60
               ) -> Figure:
    """A sweep's scalar metrics, one horizontal bar per cell (``labels``) and one panel per
    metric (its name, which carries its unit, on the axis); a failed cell (NaN) is marked
    "failed". At most ``max_cells`` cells are drawn, and the title says so."""
    names = list(metrics)
    shown_cells = min(len(labels), max_cells)
    fig, axes = plt.subplots(1, len(names), figsize=(3.2 * len(names) + 2.5, 0.28 * shown_cells + 1.4),
                             layout="constrained", squeeze=False, sharey=True)
    y = np.arange(shown_cells)
    for ax, name in zip(axes[0], names):
        values = np.asarray(metrics[name][:shown_cells], dtype=float)
        ax.barh(y, values, color="C0")       # a failed cell (NaN) draws no bar
        for k in np.flatnonzero(np.isnan(values)):
            ax.text(0.01, k, "failed", va="center", fontsize=7, color="C3",
                    transform=ax.get_yaxis_transform())
        finite = values[np.isfinite(values)]
        if finite.size and finite.min() > 0 and finite.max() > 100 * finite.min():
            ax.set_xscale("log")        # errors spanning decades: each cell's bar readable
        ax.set_xlabel(name + (" (log scale)" if ax.get_xscale() == "log" else ""), fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3, axis="x")
    axes[0, 0].set_yticks(y, labels[:shown_cells], fontsize=7)
    axes[0, 0].invert_yaxis()
    cut = f" (first {shown_cells} of {len(labels)} cells)" if shown_cells < len(labels) else ""
    fig.suptitle(title + cut, fontsize=9)
    return fig


def plot_predicted_vs_true(q_true: np.ndarray, q_pred: np.ndarray, joint_names, *,
                           max_points: int = 4000, exact: float = 1e-9) -> Figure:
    """One column per joint: predicted against true joint angle [deg] with the diagonal (top),
    and the error, predicted minus true [deg], against the true angle (bottom: errors far
    smaller than the joint's range, invisible on the diagonal, at their own scale). A joint
    whose errors are all below ``exact`` [deg] is marked as exact to rounding instead."""
    n = q_true.shape[1]
    k = np.linspace(0, len(q_true) - 1, min(max_points, len(q_true))).astype(int)
    fig, axes = plt.subplots(2, n, figsize=(2.6 * n, 5.2), layout="constrained", squeeze=False,
                             sharex="col")
    for j in range(n):
        top, bottom = axes[0, j], axes[1, j]
        t, p = np.degrees(q_true[k, j]), np.degrees(q_pred[k, j])
        top.plot(t, p, ".", ms=1.5, alpha=0.5, color=f"C{j}")
        lo, hi = float(min(t.min(), p.min())), float(max(t.max(), p.max()))
        top.plot([lo, hi], [lo, hi], color="0.3", lw=0.8)
        top.set_title(f"q{j + 1} {joint_names[j]}", fontsize=9)
        error = p - t
        if np.abs(error).max() < exact:
            bottom.text(0.5, 0.5, f"exact to rounding\n(|error| < {exact:.0e}°)", ha="center", va="center",
                        transform=bottom.transAxes, fontsize=8)
            bottom.set_yticks([])
        else:
            bottom.plot(t, error, ".", ms=1.5, alpha=0.5, color=f"C{j}")
            bottom.axhline(0.0, color="0.3", lw=0.8)
        bottom.set_xlabel("true [deg]", fontsize=8)
        for ax in (top, bottom):
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("predicted [deg]", fontsize=8)
    axes[1, 0].set_ylabel("predicted − true [deg]", fontsize=8)
    return fig


def plot_error_map(points: np.ndarray, error: np.ndarray, *, label: str, title: str = "",
                   cells: int = 28, least: int = 3) -> Figure:
    """Side view (distance from the base axis, height) of tool positions ``(N, 3)`` [m]: the
    **median** ``error`` of the positions in each hexagonal cell (``cells`` across the wider
    side; cells with fewer than ``least`` positions left blank), on a log colour scale.

    A scatter of every position (the earlier figure) overplots: 10 000 points of a 3-D region
    projected on a plane cover each other, and whichever is drawn last sets the colour, so the
    map showed the drawing order, not the error. A cell's median is what the positions there
    have in common (``matplotlib``'s ``hexbin`` with ``reduce_C_function=np.median``)."""
    from matplotlib.colors import LogNorm
    points, error = np.asarray(points, float), np.asarray(error, float)
    r, z = np.hypot(points[:, 0], points[:, 1]), points[:, 2]
    # The figure's width follows the side view's aspect (equal axes), so no width is left blank.
    span_r = float(np.ptp(r)) or 1.0
    span_z = float(np.ptp(z)) or 1.0
    fig, ax = plt.subplots(figsize=(float(np.clip(4.0 * span_r / span_z + 2.0, 3.6, 10.0)), 4.5),
                           layout="constrained")
    floor = max(float(np.percentile(error, 1)), 1e-12)
    across = max(2, int(round(cells * min(1.0, span_r / span_z))))     # hexagons about as tall as wide
    hb = ax.hexbin(r, z, C=np.maximum(error, floor), reduce_C_function=np.median, gridsize=across,
                   mincnt=least, cmap="viridis", norm=LogNorm(), linewidths=0.2, edgecolors="face")
    bar = fig.colorbar(hb, ax=ax, label=f"{label}, median per cell")
    _readable_log_axis(bar.ax.yaxis)        # "2, 3, 5, 10", not "2 × 10⁰"
    ax.set_xlabel("distance from the base axis r [m]")
    ax.set_ylabel("height z [m]")
    ax.set_aspect("equal")
    if title:
        ax.set_title(title, fontsize=10)
    return fig


def plot_error_against(x: Mapping[str, np.ndarray], error: np.ndarray, *, label: str,
                       bins: int = 12) -> Figure:
    """``error`` against each named quantity (the name carries the unit): the median and the
    95th percentile of the error in equal-count bins of the quantity. Samples whose quantity
    is not finite (NaN: it does not apply to them) are left out of that panel."""
    fig, axes = plt.subplots(1, len(x), figsize=(4.6 * len(x), 3.6), layout="constrained",
                             squeeze=False, sharey=True)
    all_errors = error
    for ax, (name, values) in zip(axes[0], x.items()):
        keep = np.isfinite(values)
        values, error = values[keep], all_errors[keep]
        ax.set_xlabel(name)
        if not values.size:
            ax.text(0.5, 0.5, "no sample has this quantity", ha="center", va="center",
                    transform=ax.transAxes)
            continue
        edges = np.unique(np.quantile(values, np.linspace(0, 1, bins + 1)))
        which = np.clip(np.searchsorted(edges, values, side="right") - 1, 0, len(edges) - 2)
        centre = 0.5 * (edges[1:] + edges[:-1])
        for q, style in ((50, "o-"), (95, "s--")):
            stat = [np.percentile(error[which == b], q) if np.any(which == b) else np.nan
                    for b in range(len(edges) - 1)]
            ax.plot(centre, stat, style, label=f"{q}th percentile" if q != 50 else "median")
        ax.set_yscale("log")
        ax.grid(alpha=0.3, which="both")
    axes[0, 0].set_ylabel(label)
    axes[0, 0].legend(fontsize=8)
    _readable_log_axis(axes[0, 0].yaxis)
    return fig


def _readable_log_axis(axis) -> None:
    """Labelled ticks on a logarithmic ``axis`` that spans too few decades for matplotlib's
    (which labels powers of ten only, so a curve between 1.1 and 4 gets a single "10⁰"): every
    digit and 1.2, 1.5, 2.5 of each decade below a span of 3, at 1, 1.5, 2, 3, 5 and 7 below
    30, at 1, 2 and 5 below 1 000, written as plain numbers. Call after the data are drawn (the limits are read)."""
    lo, hi = sorted(axis.axes.get_ylim() if axis.axis_name == "y" else axis.axes.get_xlim())
    if not (0 < lo < hi) or hi / lo >= 1000:
        return
    subs = ((1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0) if hi / lo < 3 else
            (1.0, 1.5, 2.0, 3.0, 5.0, 7.0) if hi / lo < 30 else (1.0, 2.0, 5.0))
    axis.set_major_locator(mticker.LogLocator(base=10, subs=subs))
    axis.set_major_formatter(mticker.FuncFormatter(lambda v, _: f"{v:.2g}"))
    axis.set_minor_locator(mticker.LogLocator(base=10, subs=tuple(range(1, 10))))
    axis.set_minor_formatter(mticker.NullFormatter())


def _without_specks(reached: np.ndarray, share: float = 0.02) -> np.ndarray:
    """An occupancy grid ``(nx, nz)`` without its specks: islands of reached cells, and holes of
    unreached cells enclosed by reached ones, smaller than ``share`` of the reached cells — the
    sampling's gaps and strays, which a contour would draw as fragments of outline."""
    import scipy.ndimage as ndimage

    reached = np.asarray(reached, bool).copy()
    least = share * max(int(reached.sum()), 1)
    for value in (True, False):
        labels, count = ndimage.label(reached == value)
        sizes = np.bincount(labels.ravel(), minlength=count + 1)
        border = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
        components = np.arange(1, count + 1)
        enclosed = np.ones(count, bool) if value else ~np.isin(components, border)   # a hole: off the border
        specks = components[(sizes[1:] < least) & enclosed]
        reached[np.isin(labels, specks)] = not value
    return reached


def plot_arms_compared(side: Mapping[str, np.ndarray], position_error_mm: Mapping[str, np.ndarray],
                       *, targets_mm: tuple[float, float] = (2.0, 10.0), bins: int = 60) -> Figure:
    """Two arms side by side. Left, the side view of each workspace: the outline of the cells
    (distance from the base axis, height) that tool positions ``side[name] (N, 2)`` [m] reach.
    An outline's inner curves bound places the tool cannot reach. Right, the distribution of
    each arm's learned-IK tool position error
    ``position_error_mm[name] (M,)`` [mm] (a cumulative curve, logarithmic axis) beside the
    ``targets_mm`` for its median and its 95th percentile."""
    fig, (left, right) = plt.subplots(1, 2, figsize=(11.5, 4.6), layout="constrained")
    extent = max(float(p[:, 0].max()) for p in side.values()) * 1.05
    z = np.concatenate([p[:, 1] for p in side.values()])
    margin = 0.05 * (z.max() - z.min())
    step = extent / bins
    edges = np.linspace(0, extent, bins + 1), np.arange(z.min() - margin, z.max() + margin + step, step)
    centres = [(e[1:] + e[:-1]) / 2 for e in edges]
    for k, (name, p) in enumerate(side.items()):
        counts, _, _ = np.histogram2d(p[:, 0], p[:, 1], bins=edges)
        left.contour(centres[0], centres[1], _without_specks(counts > 0).T.astype(float), levels=[0.5],
                     colors=[f"C{k}"], linewidths=2)
        left.plot([], [], color=f"C{k}", lw=2, label=f"{name}: where its tool reaches")
    left.plot(0, 0, "k+", ms=10, label="first joint's origin")
    left.set(xlabel="distance from the base axis [m]", ylabel="height z [m]", aspect="equal",
             title="Workspaces, side view")
    left.grid(alpha=0.3)
    # Below the panel: inside it the legend would hide part of an outline (the outlines hold the
    # inner boundaries too: places near the base axis the tool cannot reach).
    left.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
    for k, (name, e) in enumerate(position_error_mm.items()):
        e = np.sort(np.asarray(e, dtype=float))
        right.plot(np.maximum(e, 1e-6), np.arange(1, len(e) + 1) / len(e), color=f"C{k}", lw=2,
                   label=f"{name}: median {np.median(e):.3g} mm")
    for target, style, what in zip(targets_mm, ("--", ":"), ("median", "95th percentile")):
        right.axvline(target, color="0.4", ls=style, lw=1, label=f"{target:g} mm (target for the {what})")
    right.set(xscale="log", xlabel="learned IK: tool position error [mm]",
              ylabel="share of test poses", title="Learned IK on each arm's test poses")
    right.grid(alpha=0.3, which="both")
    # Below the panel as well: in its lower right the legend covered the slower arm's curve.
    right.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
    return fig
