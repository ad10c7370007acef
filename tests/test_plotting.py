"""Figures a reader can read (nfarm.presentation.plotting): labelled ticks on short logarithmic axes, a
constant joint drawn as constant, legends that hide no data."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from nfarm.presentation.plotting import plot_joint_paths, plot_size_curve  # noqa: E402


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
    plotting._NUMBERS.clear()
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
