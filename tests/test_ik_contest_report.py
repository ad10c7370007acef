"""The learned-IK contest as chapter 6.1 writes it down (nfarm.study.ik_contest_report): its
standings, budget, configurations, spread figure and sentences, on a contest made up here."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

from nfarm.study import contest  # noqa: E402
from nfarm.study import ik_contest_report as report  # noqa: E402
from nfarm.study.sweep import Cell, CellResult  # noqa: E402


def cell(learner, seed, p95, encoding=None, fraction=1.0, epochs=(0,), **options):
    params = {"learner": learner, "options": options, "seed": seed, "fraction": fraction,
              **({"encoding": encoding} if encoding else {})}
    metrics = {"position_p95_mm": p95, "position_p50_mm": p95 / 3, "orientation_p95_deg": p95 / 10,
               "orientation_p50_deg": p95 / 30, "train_samples": 1000 if fraction == 1.0 else 250,
               "epochs": list(epochs), "fit_seconds": 2.0, "predict_us": 3600.0}
    return CellResult(Cell(params, f"{learner}{encoding}{seed}{fraction}{sorted(options.items())}"), "ok", metrics, 3.0, "w")


@pytest.fixture
def race():
    """Three contestants: RBF and the ANFIS close (their seeds overlap), k-NN far behind (pruned)."""
    rung = [cell("anfis", 0, 3.0, "arm_plane", 0.25, (5, 5), n_rules=64),
            cell("anfis", 0, 2.0, "arm_plane", 0.25, (5, 5), n_rules=128),
            cell("anfis", 0, 2.5, "arm_plane", 0.25, (5, 5), n_rules=256),
            cell("rbf", 0, 1.5, fraction=0.25, neighbors=16), cell("rbf", 0, 1.8, fraction=0.25, neighbors=32),
            cell("rbf", 0, 1.9, fraction=0.25, neighbors=64), cell("knn", 0, 40.0, fraction=0.25, k=5)]
    tuning = [cell("anfis", 0, 1.2, "arm_plane", epochs=(9, 9), n_rules=128), cell("rbf", 0, 1.0, neighbors=16),
              cell("knn", 0, 30.0, k=5)]
    chosen = contest.choose(tuning)
    spread = [cell("anfis", 1, 1.4, "arm_plane", epochs=(9, 9), n_rules=128), cell("rbf", 1, 1.5, neighbors=16)]
    return rung, tuning, chosen, contest.standings(chosen, spread), contest.budgets(rung + tuning)


def test_formats_read_rounding_as_such():
    assert report.mm_text(0.62831) == "0.628" and report.mm_text(5e-7) == "< 1e-6"
    assert report.deg_text(5e-7, floor=1e-9) == "5e-07"
    assert report.configuration_text({"options": {"k": 5, "joint_options": {}}}) == "k=5"
    assert report.configuration_text({"options": None}) == ""


def test_the_standings_table_pairs_each_contestant_with_the_leader_seed_by_seed(race):
    _, _, _, ranked, spent = race
    table = report.contest_table(ranked, spent)
    rows = {row[0]: row for row in table.rows}
    assert [row[0] for row in table.rows] == ["RBF interpolation", "ANFIS in the arm's plane", "k nearest neighbours"]
    assert rows["RBF interpolation"][-1] == "—" and rows["RBF interpolation"][5] == "1.25 (1–1.5)"
    # ANFIS minus RBF: seed 0 +0.2, seed 1 −0.1: the range holds 0
    assert rows["ANFIS in the arm's plane"][-1] == "0.05 (-0.1 to 0.2) no difference shown"
    assert rows["k nearest neighbours"][-1] == "pruned after seed 0" and rows["k nearest neighbours"][5] == "30 (seed 0)"
    assert [row[1] for row in table.rows] == [3, 3, 1]                    # configurations tried, both rungs
    # The saved budget, machine-independent: 4 fits (3 on 250 poses, 1 on 1 000), one pass each (closed form);
    # the ANFIS's 3 rung fits ran 5 + 5 epochs on 250 poses, its promoted one 9 + 9 on 1 000
    # and its seconds, measured: 4 cells of 2 s training, 3 s each
    table = report.budget_table(ranked, spent)
    budget = {row[0]: row for row in table.rows}
    assert budget["RBF interpolation"] == ["RBF interpolation", 3, 4, "1,750", 8.0, 12.0]
    assert budget["ANFIS in the arm's plane"][:4] == ["ANFIS in the arm's plane", 3, 4, f"{3 * 250 * 10 + 1000 * 18:,}"]
    assert [c for c in table.columns if c.endswith("(measured)")] == ["tuning's training [s] (measured)",
                                                                       "tuning's cells [s] (measured)"]


def test_every_configuration_is_listed_and_the_chosen_one_marked(race):
    rung, tuning, chosen, _, _ = race
    table = report.configurations_table(rung, tuning, chosen)
    assert len(table.rows) == len(rung) + len(tuning)
    marked = [row for row in table.rows if row[-1] == "◀ chosen"]
    assert [(row[0], row[2]) for row in marked] == [("ANFIS in the arm's plane", "1,000"), ("RBF interpolation", "1,000"),
                                                     ("k nearest neighbours", "1,000")]
    assert table.rows[0][6] == "5/5" and table.rows[3][6] == "—"       # epochs run: per joint, none for RBF


def test_the_spread_figure_shows_every_seed_on_a_log_axis(race):
    fig, caption = report.spread_figure(race[3], "arm")
    assert fig.axes[0].get_xscale() == "log" and "spread" in caption
    plt.close(fig)


def test_the_prose_names_the_leader_the_tie_the_pruned_and_the_edge(race):
    rung, _, chosen, ranked, spent = race
    text = report.contest_prose(ranked, spent, rung, chosen)
    assert text.startswith("On the validation poses the leader is **RBF interpolation** (neighbors=16)")
    assert "Second is ANFIS in the arm's plane at 1.3 (1.2–1.4) mm: seed by seed the two differ by -0.1 to 0.2 mm, " \
           "**no difference shown**." in text
    assert "The contestants tried unequal numbers of configurations (ANFIS in the arm's plane 3, RBF " \
           "interpolation 3, k nearest neighbours 1)" in text
    assert ("pruned after seed 0, more than 2 times the best's 95th percentile (the best ANFIS is kept whatever its gap, "
            "for the verdict's spread): k nearest neighbours.") in text
    # RBF's 16 neighbours is the smallest of the three it tried; the ANFIS's 128 rules lie inside its search
    # with its last step on the first rung's poses: 32 → 16 neighbours, 1.8 → 1.5 mm, (1.8 - 1.5) / 1.8: not flat
    assert "RBF interpolation, neighbors=16 (the smallest tried; the step from 32 moved the validation score by +17 %)" \
        in text and "n_rules" not in text
    # ... with what the chosen fit cost on this machine, and where the sweep file says why the search stops there
    assert "one fit of each of those chosen configurations on all the training poses cost: RBF interpolation 2 s of " \
           "training, 3.6 ms a pose to predict." in text and "params/sweeps/ik_contest.yaml" in text


def test_the_prose_says_when_every_budget_is_equal_and_no_choice_is_at_an_edge(race):
    rung, _, chosen, ranked, spent = race
    equal = {name: (3, *s[1:]) for name, s in spent.items()}
    text = report.contest_prose(ranked, equal, rung[:3], chosen)
    assert "Every contestant tried 3 configurations on 25% of the training poses and its promoted one again" in text
    assert text.endswith(" No contestant's chosen configuration lies at the edge of a value its search tried.")


def test_an_arm_off_its_plane_is_said_so():
    text = report.planar_note("skew", 0.1, 0.5)
    assert text.startswith("On skew the arm's plane cannot describe the poses") and "by up to 5.73°" in text
