"""Figures a reader can read (nfarm.presentation.plotting): labelled ticks on short logarithmic axes, a
constant joint drawn as constant, legends that hide no data."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from nfarm.presentation.plotting import plot_joint_paths, plot_size_curve, plot_spread  # noqa: E402


def labelled_ticks(axis):
    axis.axes.figure.canvas.draw()
    lo, hi = sorted(axis.axes.get_ylim())
    return [t.get_text() for t in axis.get_ticklabels() if t.get_text() and lo <= t.get_position()[1] <= hi]


@pytest.mark.parametrize("low, high, least", [(1.1, 4.0, 4), (0.9, 1.3, 2), (0.05, 12.0, 4), (1e-3, 30.0, 4)])
def test_a_short_logarithmic_axis_gets_several_labelled_ticks(low, high, least):
    errors = np.geomspace(low, high, 5)[:, None] * [1.0, 0.95]
    fig = plot_size_curve([100, 200, 400, 800, 1600], errors, ["a", "b"])
    try:
        ticks = labelled_ticks(fig.axes[0].yaxis)
        assert len(ticks) >= least, ticks
    finally:
        plt.close(fig)


def test_a_joint_held_along_the_path_is_drawn_as_constant_not_as_rounding_spikes():
    s = np.linspace(0, 1, 50)
    rng = np.random.default_rng(0)
    q = np.column_stack([s, 0.5 * s, 1e-9 * rng.normal(size=50)])     # the third joint: rounding only
    fig = plot_joint_paths(s, {"a": q, "b": q + 1e-10}, ["j1", "j2", "roll"])
    try:
        axes = fig.axes[:3]
        assert axes[2].get_title() == "roll (constant)" and axes[2].get_ylim() == pytest.approx((-1, 1))
        assert axes[0].get_title() == "j1" and np.ptp(axes[0].get_ylim()) > 50
    finally:
        plt.close(fig)


def test_the_arms_figure_keeps_its_legends_off_the_data():
    from nfarm.presentation.plotting import plot_arms_compared
    rng = np.random.default_rng(1)
    side = {name: np.column_stack([rng.uniform(0, r, 5000), rng.uniform(-0.2, r, 5000)])
            for name, r in (("a", 0.5), ("b", 0.4))}
    errors = {"a": rng.lognormal(1, 1, 2000), "b": rng.lognormal(2, 1, 2000)}
    fig = plot_arms_compared(side, errors)
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        for ax in fig.axes[:2]:
            box = ax.get_legend().get_window_extent(renderer)
            assert not box.overlaps(ax.get_window_extent(renderer)), ax.get_title()
    finally:
        plt.close(fig)


def test_figures_are_numbered_by_chapter_in_the_order_shown(tmp_path):
    from nfarm.presentation import plotting
    from nfarm.presentation import numbering
    numbering.clear()
    assert plotting.figure_number(str(tmp_path / "06_ik_curves.png")) == "Figure 6.1."
    assert plotting.figure_number(str(tmp_path / "06_ik_sizes.png")) == "Figure 6.2."
    assert plotting.figure_number(str(tmp_path / "06_ik_curves.png")) == "Figure 6.1."    # shown again
    assert plotting.figure_number(str(tmp_path / "07_id_torques.png")) == "Figure 7.1."
    assert plotting.figure_number(str(tmp_path / "arm.png")) == "Figure."


def test_the_error_maps_colour_bar_reads_plain_numbers():
    """A log colour scale over one decade or two is labelled 5, 7, 10, 15, 20, not "2 × 10⁰"."""
    from nfarm.presentation.plotting import plot_error_map

    rng = np.random.default_rng(0)
    fig = plot_error_map(rng.uniform(0.1, 0.3, (3000, 3)), rng.uniform(1.5, 25, 3000), label="position error [mm]")
    fig.canvas.draw()
    labels = [t.get_text() for t in fig.axes[1].get_yticklabels() if t.get_text()]
    assert "10" in labels and not any("×" in s or "$" in s for s in labels), labels
    plt.close(fig)


def test_coinciding_series_stay_visible_each_narrower_than_the_one_under_it():
    """Three series that coincide (a model that is exact): the reference a wide band, the others
    narrower the later they come and drawn over it — none hides another."""
    from nfarm.presentation.plotting import plot_per_joint, plot_profiles
    t = np.linspace(0, 1, 20)
    a = np.column_stack([t, 2 * t])
    fig = plot_per_joint(t, {"truth": a, "exact": a, "also exact": a}, ["j1", "j2"], ylabel="τ [N·m]")
    try:
        lines = fig.axes[0].get_lines()
        widths, layers = [line.get_linewidth() for line in lines], [line.get_zorder() for line in lines]
        assert widths == sorted(widths, reverse=True) and len(set(widths)) == 3 and layers == sorted(layers)
        assert len({str(line.get_linestyle()) for line in lines}) == 3
    finally:
        plt.close(fig)
    fig = plot_profiles(t, {"position [deg]": np.column_stack([t, 0.5 * t, t])}, ["a", "b", "c"])
    try:
        widths = [line.get_linewidth() for line in fig.axes[0].get_lines()]
        assert widths[0] > widths[2], "the first of two coinciding joints is wider, so it shows around the second"
    finally:
        plt.close(fig)


def test_each_joints_torque_spread_has_its_own_axis():
    """Torques of 3 N·m and of 1e-4 N·m: on one shared axis the small ones would be a flat line."""
    from nfarm.presentation.plotting import plot_torque_distributions
    rng = np.random.default_rng(0)
    fig = plot_torque_distributions(rng.normal(size=(500, 3)) * [3.0, 0.1, 1e-4], ["a", "b", "c"])
    try:
        spans = [np.ptp(ax.get_ylim()) for ax in fig.axes]
        assert len(spans) == 3 and spans[2] < 1e-2 < spans[1] < 1 < spans[0]
    finally:
        plt.close(fig)


def test_the_workspace_outline_drops_specks_but_keeps_real_holes():
    from nfarm.presentation.plotting import _without_specks
    reached = np.zeros((40, 40), bool)
    reached[5:35, 5:35] = True
    reached[15:25, 15:25] = False          # a real hole (a tenth of the area)
    reached[8, 8] = False                  # a speck of a hole: the sampling's gap
    reached[1, 38] = True                  # a stray island
    clean = _without_specks(reached)
    assert clean[8, 8] and not clean[1, 38] and not clean[20, 20]
    assert (clean != reached).sum() == 2


def test_the_spread_plot_names_each_row_once_with_its_count_and_a_legend_only_for_the_reference():
    groups = {"ANFIS in the arm's plane": [0.5, 0.6, 0.7], "k nearest neighbours in the ANFIS's structure": [30.0]}
    fig = plot_spread(groups, ylabel="p95 [mm]")
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["ANFIS in the arm's plane (3)",
                                                            "k nearest neighbours in the ANFIS's structure (1)"]
    assert ax.get_legend() is None                       # the row labels say what a legend would repeat
    plt.close(fig)
    fig = plot_spread(groups, reference=1.0, reference_label="Jang (1993)", ylabel="p95 [mm]")
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["Jang (1993)"]
    plt.close(fig)
    fig = plot_spread(groups, ylabel="p95 [mm]", log=True)          # half a millimetre to 30: plain numbers
    fig.canvas.draw()
    lo, hi = fig.axes[0].get_xlim()
    ticks = [t.get_text() for t in fig.axes[0].xaxis.get_ticklabels() if t.get_text() and lo <= t.get_position()[0] <= hi]
    assert {"1", "2", "5", "10"} <= set(ticks), ticks
    plt.close(fig)
