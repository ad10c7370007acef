"""Solvers on the model: inverse kinematics (:mod:`.ik` gathers both kinds), iterative
(:mod:`.iterative`, its update rules in :mod:`.ik_methods`: Levenberg–Marquardt, damped least
squares, the pseudo-inverse, the Jacobian transpose) and in closed form, every branch
(:mod:`.geometric_ik`; the class of arms it solves and its branches in :mod:`.arm_class`), the
checks of the target poses and weights they share (:mod:`.arguments`), joint trajectories
(:mod:`.trajectory`), the tool paths an arm can hold (:mod:`.tool_paths`), and workspace and
singularity analysis (:mod:`.workspace`).

Imports :mod:`nfarm.model` and :mod:`nfarm.infra` only.
"""
