"""Words for numbers (nfarm.wording): every value a sentence can get reads well."""

from __future__ import annotations

import doctest

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import nfarm.wording
from nfarm.wording import about, sig, span, times, times_range


def test_the_examples_hold():
    assert doctest.testmod(nfarm.wording).failed == 0


@pytest.mark.parametrize("ratio, words", [
    (1.0, "about the same as"), (0.996, "about the same as"), (1.1, "about the same as"),
    (0.9, "about the same as"), (1.11, "1.1 times"), (0.31, "0.31 times"), (0.0612, "0.061 times"),
    (9.96, "10 times"), (52.3, "52 times"), (994.1, "990 times"), (0.0, "0 times"),
])
def test_a_ratio_near_one_is_about_the_same_and_others_have_two_digits(ratio, words):
    assert times(ratio) == words


@pytest.mark.parametrize("lo, hi, words", [
    (0.996, 1.0, "about the same as"), (1.2, 52.0, "1.2–52 times"), (52.0, 1.2, "1.2–52 times"),
    (2.0, 2.04, "2.0 times"), (0.06, 994.0, "0.060–990 times"),
])
def test_a_range_of_ratios(lo, hi, words):
    assert times_range(lo, hi) == words


def test_wall_clock_figures_have_two_significant_digits():
    assert about(1_436_799) == "about 1,400,000" and about(994_128) == "about 990,000"
    assert about(10.4) == "about 10" and about(0.0123) == "about 0.012"


def test_a_span_of_equal_values_is_one_value():
    assert span(0.125, 0.125) == "0.125" and span(0.1, 0.25) == "0.1–0.25"


@settings(max_examples=200, deadline=None)
@given(st.floats(min_value=1e-6, max_value=1e9))
def test_no_ratio_reads_as_one_times_or_in_exponent_form(ratio):
    words = times(ratio)
    assert words != "1 times" and "e+" not in words and "e-" not in words and "1.0 times" != words


def test_a_ratio_must_be_finite():
    with pytest.raises(ValueError, match="finite"):
        times(float("nan"))


def test_timings_in_tables_have_three_significant_digits():
    assert sig(186704.3) == "187,000" and sig(191.94) == "192" and sig(0.0012345) == "0.00123" and sig(5211.2) == "5,210"


def test_torque_columns_mark_the_joints_below_the_sensor_noise():
    from nfarm.wording import torque_columns
    headers, note = torque_columns([2.0, 0.0001], [0.005, 0.005], ["base", "roll"])
    assert headers == ["τ1 [%]", "τ2 [%] (below noise)"]
    assert note.startswith(". The torque of τ2 (roll: spread 0.0001 N·m, sensor noise σ 0.005 N·m) is below")
    assert not note.endswith(".")                       # the captions it ends have no final stop
    assert " it, and its NRMSE" in note
    headers, note = torque_columns([1e-4, 2e-4], [0.005, 0.005], ["a", "b"], unit="N·m")
    assert headers == ["τ1 [N·m] (below noise)", "τ2 [N·m] (below noise)"] and " are below " in note and "them" in note
    assert torque_columns([2.0, 3.0], [0.005, 0.005], ["a", "b"]) == (["τ1 [%]", "τ2 [%]"], "")
    assert torque_columns([1e-9, 3.0], None, ["a", "b"]) == (["τ1 [%]", "τ2 [%]"], "")
