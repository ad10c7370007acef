"""The update rules of the iterative inverse kinematics (:func:`nfarm.solvers.ik.solve`).

Each rule is a small object that carries and checks its own options (one ``ValueError`` line
naming the option) and supplies the step of every lane (one attempt at one target) from ``e``,
the pose error of :func:`nfarm.model.rotations.pose_error`, and ``J``, the geometric Jacobian,
both scaled by the square roots of the solve's ``weights`` (``E = ½ eᵀe``)::

    LM()    "lm"    Levenberg–Marquardt   (JᵀJ + λI) Δq = Jᵀe, λ adaptive (see ``damping``)
    DLS()   "dls"   damped least squares  (JᵀJ + μ²I) Δq = Jᵀe, μ fixed     (Wampler 1986)
    Pinv()  "pinv"  Newton–Raphson        Δq = J⁺ e  (truncated-SVD pseudo-inverse)
    JT()    "jt"    Jacobian transpose    Δq = α Jᵀe, α = ⟨e, JJᵀe⟩ / ‖JJᵀe‖² (Buss 2009)

``solve(robot, T, method=LM(damping="marquardt"))`` picks one with its options; a name picks
one with its defaults. ``LM(damping="sugihara")`` (default) is Sugihara's (2011) rule
``λ = s·E + w̄``: the damping vanishes with the error, so the last iterations are Gauss–Newton
(quadratic convergence).
``"marquardt"`` is the classic schedule (λ ÷ ν after a step that lowers E, × ν after one that
does not). Both keep the last accepted point and retry from it with ν times the damping after
a step that raised E (for Sugihara's rule, a multiplier ≥ 1 of s·E + w̄): far from a solution,
and always for an unreachable target, the Gauss–Newton model is poor and an unguarded step can
climb. Measured on 10 000 reachable intelbot5 targets (``benchmarks/bench_ik.py``), Sugihara's
rule needs fewer steps for the same success (9.1 against 10.5 per target), so it is the
default. Our constants differ from Sugihara's (s = 1, w̄ = 1e-3): s = 0.1 takes bolder steps
far from the target (9.1 against 10.8 steps per target), and w̄ = 1e-12 lets the steps become
Gauss–Newton near targets next to a singularity, where w̄ = 1e-8 slows convergence to a crawl
(0.06 % of the targets then run out of steps).

Arrays are in component layout, lanes last: ``e (6, A)``, ``J (6, n, A)``, ``Δq (n, A)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..infra.arguments import check_number
from ..model.linalg import cholesky_solve_T, gram_T

__all__ = ["Method", "LM", "DLS", "Pinv", "JT", "METHODS", "method_of"]


@dataclass(frozen=True)
class Method:
    """An update rule of :func:`nfarm.solvers.ik.solve`: its options (checked when it is made, one line naming the
    option) and its step ``Δq (n, A)`` from the scaled Jacobians ``J (6, n, A)``, errors ``e (6,
    A)``, ``E (A,)`` and each lane's damping state ``lam (A,)``.

    ``max_iter``: the steps per attempt a solve gives it unless told otherwise. A ``guarded``
    rule keeps each lane's last accepted point and steps from it again with more damping after
    a step that raised E (:meth:`adapt`).

    Example:
        >>> J = np.zeros((6, 5, 3)); J[:5] = np.eye(5)[:, :, None]     # J (6, n, A): Δq = e[:5]
        >>> e = np.ones((6, 3))                                          # e (6, A)
        >>> dq = Pinv().step(J, e, 0.5 * (e * e).sum(0), np.ones(3))     # Δq (n, A)
        >>> dq.shape, bool(np.allclose(dq, 1.0))
        ((5, 3), True)
        >>> all(isinstance(METHODS[name](), Method) for name in METHODS)
        True
    """

    name: ClassVar[str]
    max_iter: ClassVar[int]
    guarded: ClassVar[bool] = False

    def initial_damping(self) -> float:
        """The damping state a new lane starts with."""
        return 1.0

    def step(self, J: np.ndarray, e: np.ndarray, E: np.ndarray, lam: np.ndarray) -> np.ndarray:
        """The step ``Δq (n, A)`` of every lane."""
        raise NotImplementedError

    def adapt(self, lam: np.ndarray, accept: np.ndarray) -> np.ndarray:
        """A guarded rule's damping state after a step that was accepted (``accept``) or not."""
        return lam


@dataclass(frozen=True)
class LM(Method):
    """Levenberg–Marquardt: ``(JᵀJ + λI) Δq = Jᵀe`` (module docstring).

    Args:
        damping: ``"sugihara"`` (λ = ν · (scale · E + bias), the multiplier ν starting at 1) or
            ``"marquardt"`` (λ from ``lambda0``); either way ÷ ``factor`` after an accepted
            step, × ``factor`` after a rejected one.
        scale, bias: Sugihara's ``s`` and ``w̄`` (not both 0).
        lambda0: Marquardt's first λ.
        factor: ν's step, > 1.

    Example:
        >>> LM(damping="marquardt").name, LM.max_iter
        ('lm', 25)
        >>> LM(factor=1.0)
        Traceback (most recent call last):
        ...
        ValueError: LM: factor must be a finite number > 1, got 1.0
    """

    name: ClassVar[str] = "lm"
    max_iter: ClassVar[int] = 25
    guarded: ClassVar[bool] = True
    damping: str = "sugihara"
    scale: float = 0.1
    bias: float = 1e-12
    lambda0: float = 1e-3
    factor: float = 10.0

    def __post_init__(self) -> None:
        if self.damping not in ("sugihara", "marquardt"):
            raise ValueError(f"LM: damping must be 'sugihara' or 'marquardt', got {self.damping!r}")
        check_number("LM: lambda0", self.lambda0, 0, None, open_lo=True)
        check_number("LM: factor", self.factor, 1, None, open_lo=True)
        for name in ("scale", "bias"):
            check_number(f"LM: {name}", getattr(self, name), 0, None, open_lo=False)
        if self.damping == "sugihara" and self.scale == 0 and self.bias == 0:
            raise ValueError("LM: scale and bias must not both be 0 (no damping at all)")

    @property
    def marquardt(self) -> bool:
        return self.damping == "marquardt"

    def initial_damping(self) -> float:
        return self.lambda0 if self.marquardt else 1.0

    def step(self, J, e, E, lam):
        return _step_lm(J, e, lam if self.marquardt else lam * (self.scale * E + self.bias))

    def adapt(self, lam, accept):
        floor = 1e-15 if self.marquardt else 1.0
        return np.where(accept, np.maximum(lam / self.factor, floor), np.minimum(lam * self.factor, 1e15))


@dataclass(frozen=True)
class DLS(Method):
    """Damped least squares: ``(JᵀJ + μ²I) Δq = Jᵀe`` with a fixed ``damping`` μ [m].

    Example:
        >>> DLS().damping, DLS.max_iter
        (0.05, 100)
    """

    name: ClassVar[str] = "dls"
    max_iter: ClassVar[int] = 100
    damping: float = 0.05

    def __post_init__(self) -> None:
        check_number("DLS: damping", self.damping, 0, None, open_lo=True)

    def step(self, J, e, E, lam):
        return _step_lm(J, e, self.damping ** 2)


@dataclass(frozen=True)
class Pinv(Method):
    """Newton–Raphson through the pseudo-inverse: ``Δq = J⁺ e``, singular values below ``rcond``
    times the largest cut off.

    Example:
        >>> Pinv(rcond=1e-8).rcond, Pinv.max_iter
        (1e-08, 50)
    """

    name: ClassVar[str] = "pinv"
    max_iter: ClassVar[int] = 50
    rcond: float = 1e-6

    def __post_init__(self) -> None:
        check_number("Pinv: rcond", self.rcond, 0, 1, open_lo=True)

    def step(self, J, e, E, lam):
        return _step_pinv(J, e, self.rcond)


@dataclass(frozen=True)
class JT(Method):
    """The Jacobian transpose with Buss's step length: ``Δq = α Jᵀe``, ``α = ⟨e, JJᵀe⟩ / ‖JJᵀe‖²``.

    Example:
        >>> JT().name, JT.max_iter
        ('jt', 2000)
    """

    name: ClassVar[str] = "jt"
    max_iter: ClassVar[int] = 2000

    def step(self, J, e, E, lam):
        return _step_jt(J, e)


#: The update rules by name: ``solve(..., method="dls")`` is ``method=DLS()``.
METHODS: dict[str, type[Method]] = {cls.name: cls for cls in (LM, DLS, Pinv, JT)}


def method_of(method: "str | Method") -> Method:
    """``method`` as an update rule: a :class:`Method` as given, a name of :data:`METHODS` with
    its defaults.

    Example:
        >>> method_of("dls")
        DLS(damping=0.05)
    """
    if isinstance(method, Method):
        return method
    if isinstance(method, str) and method in METHODS:
        return METHODS[method]()
    raise ValueError(f"method must be one of {', '.join(METHODS)} or an update rule (LM(), DLS(), Pinv(), "
                     f"JT()), got {method!r}")


def _step_lm(J, e, damping):
    A = gram_T(J)
    for i in range(J.shape[1]):
        A[i, i] += damping
    return cholesky_solve_T(A, np.einsum("kim,km->im", J, e))


def _step_pinv(J, e, rcond):
    Jn = np.moveaxis(J, -1, 0)
    return np.einsum("mik,mk->im", np.linalg.pinv(Jn, rcond=rcond), e.T)


def _step_jt(J, e):
    g = np.einsum("kim,km->im", J, e)
    Jg = np.einsum("kim,im->km", J, g)
    denominator = np.einsum("km,km->m", Jg, Jg)
    alpha = np.einsum("km,km->m", e, Jg) / np.where(denominator > 0, denominator, 1.0)
    return alpha * g
