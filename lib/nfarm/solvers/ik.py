"""Inverse kinematics: joint angles for target tool poses, batched over targets.

Two kinds of solver. :func:`closed_form` (module :mod:`nfarm.solvers.geometric_ik`) gives every
solution of every pose in closed form for the arms it covers (a base yaw, three parallel
pitch joints and a roll: both arms of the study); it is the exact reference. :func:`solve`
(module :mod:`nfarm.solvers.iterative`) iterates from a starting guess for any chain, as the
dissertation does; its result says which closed-form branch it converged to where the robot
has one (:func:`branch_of`, module :mod:`nfarm.solvers.arm_class`). Its update rules are in
:mod:`nfarm.solvers.ik_methods`.

This module only gathers them, so that one import serves both (``nfarm.ik.solve``,
``nfarm.ik.closed_form``); the modules it gathers never import it.
"""

from __future__ import annotations

from .arguments import check_targets
from .arm_class import BRANCHES, branch_of, class_refusal, in_class
from .geometric_ik import ClosedFormResult, closed_form, count_distinct
from .ik_methods import DLS, JT, LM, METHODS, Method, Pinv
from .iterative import REASONS, IKResult, solve, solve_path

__all__ = ["IKResult", "solve", "solve_path", "check_targets", "METHODS", "REASONS", "Method", "LM", "DLS",
           "Pinv", "JT", "closed_form", "ClosedFormResult", "BRANCHES", "branch_of", "in_class",
           "class_refusal", "count_distinct"]
