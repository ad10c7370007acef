"""Words for numbers (nfarm.presentation.wording): every value a sentence can get reads well."""

from __future__ import annotations

import doctest

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import nfarm.presentation.wording
from nfarm.presentation.wording import about, range_text, sig, times, times_range


def test_the_examples_hold():
    assert doctest.testmod(nfarm.presentation.wording).failed == 0


@pytest.mark.parametrize("ratio, words", [
    (1.0, "about the same as"), (0.996, "about the same as"), (1.1, "about the same as"),
    (0.9, "about the same as"), (1.11, "1.1 times"), (0.31, "31 % of"), (0.0612, "6.1 % of"),
    (0.0100, "1.0 % of"), (9.96, "10 times"), (52.3, "52 times"), (994.1, "990 times"), (0.0, "0 % of"),
])
def test_a_ratio_near_one_is_about_the_same_and_others_have_two_digits(ratio, words):
    """Below one, a share ("31 % of the error"), not "0.31 times", which reads as a gain."""
    assert times(ratio) == words


@pytest.mark.parametrize("lo, hi, words", [
    (0.996, 1.0, "about the same as"), (1.2, 52.0, "1.2–52 times"), (52.0, 1.2, "1.2–52 times"),
    (2.0, 2.04, "2.0 times"), (0.06, 994.0, "0.060–990 times"), (0.4, 0.8, "40–80 % of"), (0.5, 0.502, "50 % of"),
])
def test_a_range_of_ratios(lo, hi, words):
    assert times_range(lo, hi) == words


def test_wall_clock_figures_have_two_significant_digits():
    assert about(1_436_799) == "about 1,400,000" and about(994_128) == "about 990,000"
    assert about(10.4) == "about 10" and about(0.0123) == "about 0.012"


def test_a_range_of_values_that_print_alike_is_one_value():
    assert range_text(0.125, 0.125) == "0.125" and range_text(0.1, 0.25) == "0.1–0.25"
    assert range_text(0.12501, 0.12504) == "0.125" and range_text(1.0, 2.0, ".2f") == "1.00–2.00"


@settings(max_examples=200, deadline=None)
@given(st.floats(min_value=1e-6, max_value=1e9))
def test_no_ratio_reads_as_one_times_or_in_exponent_form(ratio):
    words = times(ratio)
    assert words != "1 times" and "e+" not in words and "e-" not in words and "1.0 times" != words
    assert not (words.startswith("0.") and words.endswith("times")) and words != "100 % of"


def test_a_ratio_must_be_finite():
    with pytest.raises(ValueError, match="finite"):
        times(float("nan"))


def test_timings_in_tables_have_three_significant_digits():
    assert sig(186704.3) == "187,000" and sig(191.94) == "192" and sig(0.0012345) == "0.00123" and sig(5211.2) == "5,210"


def test_torque_columns_mark_the_joints_below_the_sensor_noise():
    from nfarm.presentation.wording import torque_columns
    headers, note = torque_columns([2.0, 0.0001], [0.005, 0.005], ["base", "roll"])
    assert headers == ["τ1 [%]", "τ2 [%] (below noise)"]
    assert note.startswith(". The torque of τ2 (roll: spread 0.0001 N·m, sensor noise σ 0.005 N·m) is below")
    assert not note.endswith(".")                       # the captions it ends have no final stop
    assert " it, and its NRMSE" in note and note.endswith("the worst joint is taken over the others")
    headers, note = torque_columns([1e-4, 2e-4], [0.005, 0.005], ["a", "b"], unit="N·m")
    assert headers == ["τ1 [N·m] (below noise)", "τ2 [N·m] (below noise)"] and " are below " in note and "them" in note
    assert "taken over the others" not in note              # every joint below: the worst is over them all
    assert torque_columns([2.0, 3.0], [0.005, 0.005], ["a", "b"]) == (["τ1 [%]", "τ2 [%]"], "")
    assert torque_columns([1e-9, 3.0], None, ["a", "b"]) == (["τ1 [%]", "τ2 [%]"], "")


@pytest.mark.parametrize("items, words", [
    ([], ""), (["q1"], "q1"), (["q1", "q5"], "q1 and q5"), (("a", "b", "c"), "a, b and c"),
    ((f"q{j}" for j in (2, 3, 4, 5)), "q2, q3, q4 and q5"),
])
def test_names_in_a_sentence_end_with_and(items, words):
    from nfarm.presentation.wording import listed
    assert listed(items) == words


@pytest.mark.parametrize("spread, noise, resolved, words", [
    ([2.0, 1.0, 0.5, 0.1, 1e-4], [0.005] * 5, [True, True, True, True, False], "worst of τ1–τ4"),
    ([2.0, 1e-4, 0.5, 0.1, 3.0], [0.005] * 5, [True, False, True, True, True], "worst of τ1, τ3, τ4 and τ5"),
    ([2.0, 1e-4], [0.005] * 2, [True, False], "worst of τ1"),
    ([2.0, 1e-9], None, [True, True], "worst"),                       # no sensor declared: every joint
    ([1e-4, 1e-4], [0.005] * 2, [True, True], "worst"),               # none resolved: every joint counts
    ([0.005, 0.1], [0.005, 0.005], [True, True], "worst"),             # at the noise: resolved
])
def test_the_worst_joint_is_over_the_joints_a_sensor_resolves(spread, noise, resolved, words):
    from nfarm.presentation.wording import worst_of
    from nfarm.study.statistics import resolved_joints
    assert resolved_joints(spread, noise).tolist() == resolved
    assert worst_of(resolved) == words
