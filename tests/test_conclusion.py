"""The verdict in a reader's words (nfarm.publishing.conclusion): the conclusion's sentences from
the verdict rows and chapter 7's table of LM's starts, and the verdict table's cells with each
method named in words a reader knows."""

from __future__ import annotations

import numpy as np
import pytest

from test_verdict_rows import published_verdicts

from nfarm.publishing.conclusion import conclusion, reader_label, verdict_display
from nfarm.study.paired import seed_comparison
from nfarm.study.result_tables import read_verdicts
from nfarm.study.rows import WORST_ID
from nfarm.study.verdict_rows import task_verdict, verdict_table


def test_the_conclusion_says_the_wins_the_losses_the_ties_the_solver_s_starts_and_what_to_use(tmp_path):
    _, rows = published_verdicts(tmp_path)
    warm = [{"start": "home (the dissertation's)", "targets": "2000", "mean iterations": "5.99", "max iterations": "9"},
            {"start": "ANFIS prediction", "targets": "2000", "mean iterations": "2.07", "max iterations": "3"},
            {"start": "RBF interpolation (contest) prediction", "targets": "2000", "mean iterations": "2.24",
             "max iterations": "4"},
            {"start": "closed form (the region's solution)", "targets": "2000", "mean iterations": "0.00",
             "max iterations": "0"}]
    said = conclusion(rows, {"arm A": warm})
    assert len(said) == 5 and all(s.count(". ") == 0 for s in said), said        # five sentences at most
    assert said[0] == ("ANFIS is better than every other method it was compared with, beyond the paired interval, on "
                       "inverse kinematics (arm A, by 4 mm of position p95).")
    assert said[1] == ("Another method is better than ANFIS, beyond the paired interval, on rigid-body inverse dynamics "
                       f"(arm A: ridge, by 2.5 percentage points of {WORST_ID}); and no difference between ANFIS and its "
                       "best rival is shown (the paired interval, or Holm's correction for the arm's comparisons) on "
                       "measured arm, generic (arm B: MLP, 2 (-1 to 5) percentage points).")    # the tier not repeated
    assert said[2] == ("What the ANFIS gives the exact solver, as measured: started from its prediction, "
                       "Levenberg–Marquardt needs on average 2.07 (at most 3) iterations against 5.99 (at most 9) from "
                       "the home pose and 2.24 (at most 4) from the prediction of RBF interpolation (arm A); from the "
                       "closed form's solution, none; whether such a start saves seconds depends on what the "
                       "prediction costs, which chapter 7 times on the reader's machine."), said[2]
    assert said[3] == ("The study's targets the ANFIS meets on the whole interval: inverse kinematics (arm A) 3 of 3.")
    assert said[4] == ("What to use, by the held-out data: inverse kinematics, the closed form (exact; of the learned "
                       "methods, ANFIS); rigid-body inverse dynamics, ridge.")
    assert conclusion(rows)[2] == said[3]                   # without chapter 7's starts, no such sentence


def test_the_verdict_is_judged_over_seeds_and_units_and_shown_in_a_readers_words(tmp_path):
    """Two methods whose seeds differ by a constant: the gap's interval is that constant; a method
    whose seeds scatter gets a wider interval than one seed's; the table keeps the configuration,
    the display shows each value with its interval in plain words; a pruned method (one seed) is
    paired on the seed both have."""
    rng = np.random.default_rng(7)
    base = np.abs(rng.normal(size=(1, 30, 1 + 3 * 2))) + 1.0
    scatter = np.array([1.0, 1.5, 2.0, 2.5, 3.0])[:, None, None]
    a = np.repeat(base, 5, axis=0)
    a[..., 1:3] *= scatter                                   # the ANFIS's squared errors vary by seed
    b = a.copy()
    b[..., 1:3] *= 4.0                                       # the rival's: four times each seed's, RMSE twice
    est, gap = seed_comparison({"ANFIS (affine)": a, "ridge (basis=chain, alpha=1e-06)": b}, "ANFIS (affine)",
                               "ridge (basis=chain, alpha=1e-06)", WORST_ID, normalised=False, draws=300)
    assert gap.high < 0 and est["ANFIS (affine)"].seeds == 5 and gap.seeds == 5
    one = seed_comparison({"x": a[:1], "y": b}, "x", "y", WORST_ID, normalised=False, draws=300)
    assert one[1].seeds == 1 and one[0]["x"].seeds == 1
    assert est["ANFIS (affine)"].high - est["ANFIS (affine)"].low > 2 * (one[0]["x"].high - one[0]["x"].low)
    with pytest.raises(ValueError, match="the same test units"):
        seed_comparison({"x": a, "y": b[:, :10]}, "x", "y", WORST_ID, normalised=False, draws=300)
    v = task_verdict("arm", "rigid-body inverse dynamics", WORST_ID, "N·m", {n: e.value for n, e in est.items()},
                     "ANFIS (affine)", (gap.value, gap.low, gap.high),
                     intervals={n: (e.low, e.high) for n, e in est.items()}, interval="two-level, 5 seeds × 30")
    verdict_table([v]).save(tmp_path, "07_verdict")
    rows = read_verdicts(tmp_path / "tables" / "07_verdict.csv")
    assert rows[0]["rival"] == "ridge (basis=chain, alpha=1e-06)" and rows[0]["interval"] == "two-level, 5 seeds × 30"
    shown_ = verdict_display(rows)[0]
    assert shown_[3].startswith(f"ANFIS, {rows[0]['anfis_value']} ({rows[0]['anfis_low']}–{rows[0]['anfis_high']}) N·m")
    assert shown_[4].startswith("ridge regression on the chain's trigonometric basis, ")
    exact = {**rows[0], "rival_value": "< 1e-6", "rival_low": "< 1e-6", "rival_high": "< 1e-6"}
    assert verdict_display([exact])[0][4] == "ridge regression on the chain's trigonometric basis, < 1e-6 N·m"
    assert reader_label("ANFIS, dissertation's design (own, assumed)") == "ANFIS, dissertation's design (own, assumed)"
    assert reader_label("ANFIS, structure-informed (affine)") == "ANFIS, structure-informed"
