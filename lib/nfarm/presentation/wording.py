"""Words for numbers in the chapters' computed prose: a sentence built from a value must read
well for every value it can take.

The chapters' result sentences are f-strings over measured values; a ratio of 0.996 printed as
"0.996–1 times", a wall-clock rate printed to seven digits, or "1 times" read as errors. These
helpers choose the words and the precision from the value:

>>> times(1.04)
'about the same as'
>>> times(3.14159)
'3.1 times'
>>> times_range(0.996, 1.0)
'about the same as'
>>> times_range(1.2, 52.0)
'1.2–52 times'
>>> about(1_436_799)
'about 1,400,000'
>>> sig(186704.3)
'187,000'
>>> range_text(0.125, 0.125), range_text(0.1, 0.25)
('0.125', '0.1–0.25')
"""

from __future__ import annotations

import math

__all__ = ["times", "times_range", "about", "listed", "sig", "range_text", "worst_of", "torque_columns", "ordinal"]

#: Ratios within this of 1 read as "about the same": measured ratios of timings and errors
#: move by several per cent between runs and seeds.
SAME = 0.1


def _ratio(r: float, digits: int = 2) -> str:
    """A ratio to ``digits`` significant digits, but never in exponent form."""
    if not math.isfinite(r):
        raise ValueError(f"a ratio must be finite, got {r!r}")
    if r == 0:
        return "0"
    rounded = float(f"{r:.{digits}g}")
    return f"{rounded:,.{max(0, digits - 1 - math.floor(math.log10(abs(rounded))))}f}"


def times(r: float, *, same: float = SAME) -> str:
    """``r`` as the words before "that of …" or a noun: "about the same as" within ``same`` of
    1; "2.3 times", "52 times" above; "41 % of", "1.0 % of" below (two significant digits):
    "0.41 times the error" reads as a gain where it is a fraction."""
    if abs(r - 1) <= same + 1e-12:         # (1.1 - 1 is 0.10000000000000009)
        return "about the same as"
    return f"{_ratio(r)} times" if r > 1 else f"{_ratio(100 * r)} % of"


def times_range(lo: float, hi: float, *, same: float = SAME) -> str:
    """A range of ratios, before a noun as :func:`times`: "about the same as" when both ends
    are within ``same`` of 1, one ratio when both ends read alike, "40–80 % of" when both are
    below 1, else "1.2–52 times"."""
    if lo > hi:
        lo, hi = hi, lo
    if abs(lo - 1) <= same + 1e-12 and abs(hi - 1) <= same + 1e-12:
        return "about the same as"
    if hi < 1:                              # every ratio a share: "80–95 % of"
        a, b = _ratio(100 * lo), _ratio(100 * hi)
        return f"{a} % of" if a == b else f"{a}–{b} % of"
    a, b = _ratio(lo), _ratio(hi)
    return f"{a} times" if a == b else f"{a}–{b} times"


def listed(items) -> str:
    """Names in a sentence: "a", "a and b", "a, b and c" (``items``: any iterable of text)."""
    items = [str(x) for x in items]
    return " and ".join(items) if len(items) <= 2 else f"{', '.join(items[:-1])} and {items[-1]}"


def sig(x: float, digits: int = 3) -> str:
    """``x`` to ``digits`` significant digits in plain notation: ``sig(186704.3) == '187,000'``,
    ``sig(0.0012345) == '0.00123'`` (a timing in a table, not a value to seven digits)."""
    return _ratio(x, digits)


def about(x: float, digits: int = 2) -> str:
    """A wall-clock figure (a rate, a time) to ``digits`` significant digits, with "about":
    the machine's load moves it by more than the digits printed."""
    return f"about {_ratio(x, digits)}"


def range_text(lo: float, hi: float, fmt: str = ".3g") -> str:
    """The range from ``lo`` to ``hi`` as text, each written by ``fmt``: ``"lo–hi"``, or one
    value when both print alike (a range of counts over seeds is
    :func:`nfarm.study.configurations.span`)."""
    a, b = format(lo, fmt), format(hi, fmt)
    return a if a == b else f"{a}–{b}"


def worst_of(resolved) -> str:
    """The words for the worst joint over ``resolved (n,)`` bool (:func:`nfarm.study.statistics.resolved_joints`):
    "worst" when every joint counts, else "worst of τ1–τ4" (a run of joints) or "worst of τ1,
    τ2 and τ4" — a table's header and a sentence say over which joints the worst is taken."""
    joints = [j + 1 for j, r in enumerate(resolved) if r]
    if len(joints) == len(resolved):
        return "worst"
    if len(joints) > 2 and joints == list(range(joints[0], joints[-1] + 1)):
        return f"worst of τ{joints[0]}–τ{joints[-1]}"
    return "worst of " + listed(f"τ{j}" for j in joints)


def torque_columns(spread, noise, joint_names, unit: str = "%") -> tuple[list[str], str]:
    """Headers ``τj [unit]`` for a table's torque columns, and the sentence its caption adds.

    A joint whose torque spread (``spread (n,)``, the standard deviation the NRMSE divides by
    [N·m]) is below its sensor's noise σ (``noise (n,)`` [N·m], or ``None``: no sensor
    declared) has a torque no sensor of the measured arm resolves (:func:`nfarm.study.statistics.resolved_joints`):
    its header is marked "(below noise)" and the sentence names it with both values, so its
    NRMSE is read as what it is, not as evidence for or against a model, and says that the worst
    joint is taken over the others. The sentence ("" when no joint is) ends a
    caption without a final stop, as the report's captions are: it starts with ". ".
    """
    n = len(joint_names)
    below = [False] * n if noise is None else [float(s) < float(e) for s, e in zip(spread, noise)]
    headers = [f"τ{j + 1} [{unit}]" + (" (below noise)" if below[j] else "") for j in range(n)]
    parts = [f"τ{j + 1} ({joint_names[j]}: spread {float(spread[j]):.2g} N·m, sensor noise σ "
             f"{float(noise[j]):.2g} N·m)" for j in range(n) if below[j]]
    if not parts:
        return headers, ""
    verb = "is" if len(parts) == 1 else "are"
    # The captions it ends carry no final stop: it begins one sentence and ends without.
    return headers, (f". The torque of {' and '.join(parts)} {verb} below the noise of the measured arm's sensors: "
                     f"no sensor would resolve {'it' if len(parts) == 1 else 'them'}, and {'its' if len(parts) == 1 else 'their'} "
                     f"NRMSE is shown but is not evidence for or against a model"
                     + (", and the worst joint is taken over the others" if not all(below) else ""))


def ordinal(n: int) -> str:
    """``n`` as an English ordinal: ``"1st"``, ``"2nd"``, ``"32nd"``, ``"11th"``.

    Example:
        >>> [ordinal(k) for k in (1, 2, 3, 4, 11, 12, 13, 21, 32, 64)]
        ['1st', '2nd', '3rd', '4th', '11th', '12th', '13th', '21st', '32nd', '64th']
    """
    n = int(n)
    return f"{n}{'th' if 11 <= n % 100 <= 13 else {1: 'st', 2: 'nd', 3: 'rd'}.get(n % 10, 'th')}"
