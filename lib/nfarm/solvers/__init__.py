"""Solvers on the model: inverse kinematics by damped least squares and Levenberg–Marquardt
(:mod:`.ik`) and in closed form, every branch (:mod:`.geometric_ik`), joint trajectories
(:mod:`.trajectory`), the tool paths an arm can hold (:mod:`.tool_paths`), and workspace and
singularity analysis (:mod:`.workspace`).

Imports :mod:`nfarm.model` and :mod:`nfarm.infra` only.
"""
