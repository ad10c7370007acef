"""The arm panel's response to a slider move, driven through the widgets' callbacks.

Target (issue 24): a joint slider's move redraws in ≤ 100 ms median on 2 cores. Measured per
move: the slider's value set (its callback computes the pose, updates the readout and moves
the drawn lines) and the drawing sent to the page (``canvas.draw()`` for a full draw: what the
page asks for after ``draw_idle``; the blit and its image difference for the panel's way). The
peer is the same figure drawn in full on every move, in the same run; and, for scale, a new
figure per move as a notebook cell that re-plots would (``plotting.plot_arm_poses``).
"""

from __future__ import annotations

import time

import matplotlib.pyplot as plt
import numpy as np

from common import best_of
from nfarm.publishing.panel import ArmPanel
from nfarm.presentation.plotting import plot_arm_poses
from nfarm.presentation.tables import Table

MOVES = 60
TARGET_MS = 100.0


def timings(fn, values) -> np.ndarray:
    out = []
    for v in values:
        start = time.perf_counter()
        fn(v)
        out.append(time.perf_counter() - start)
    return np.array(out) * 1e3


def main() -> None:
    rows = []
    for name in ("intelbot5", "so101", "puma560"):
        panel = ArmPanel(name)
        page = panel.fk
        canvas = page.view.canvas
        canvas.draw()                       # the page's first full draw: the background exists
        slider = page.sliders[1]
        values = np.linspace(slider.min, slider.max, MOVES)

        def blitted(v):
            slider.value = float(v)         # the callback blits the moved lines

        def full(v):
            slider.value = float(v)
            canvas.draw()                   # the figure drawn in full after the move

        def new_figure(v):
            q = page.q.copy()
            q[1] = np.radians(v)
            fig = plot_arm_poses(panel.robot, {"q": q})
            fig.canvas.draw()
            plt.close(fig)

        t_blit, t_full = timings(blitted, values), timings(full, values)
        t_new = timings(new_figure, values[:10])
        median = float(np.median(t_blit))
        verdict = f"target ≤ {TARGET_MS:g} ms median: {'met' if median <= TARGET_MS else 'NOT met'}"
        rows.append([name, median, float(np.percentile(t_blit, 95)), float(np.median(t_full)),
                     float(np.median(t_new)), float(np.median(t_full)) / median, verdict])
        build = best_of(lambda: ArmPanel(name), repeat=1)
        rows[-1].insert(1, build)
    print(Table(["robot", "panel built [s]", "slider move, panel [ms] median", "p95 [ms]",
                 "move + full draw [ms] median", "move + new figure [ms] median", "full / panel", "note"], rows,
                floatfmt=["", ".2f", ".1f", ".1f", ".1f", ".1f", ".1f", ""]).to_markdown())


if __name__ == "__main__":
    main()
