"""nfarm — a reproducible study of a 5-DOF arm: DH kinematics, Levenberg–Marquardt inverse
kinematics, recursive Newton–Euler dynamics and ANFIS (Jang 1993).

Modules: :mod:`~nfarm.robot` (parameters and validation), :mod:`~nfarm.kinematics`,
:mod:`~nfarm.rotations`, :mod:`~nfarm.ik`, :mod:`~nfarm.dynamics`, :mod:`~nfarm.trajectory`,
:mod:`~nfarm.anfis` (with :mod:`~nfarm.fuzzy`), :mod:`~nfarm.jang` (Jang's benchmark problems), :mod:`~nfarm.urdf`,
:mod:`~nfarm.recording` (rerun), :mod:`~nfarm.workspace`, :mod:`~nfarm.linalg`,
:mod:`~nfarm.pinocchio_ref` (the independent reference model), :mod:`~nfarm.plotting`,
:mod:`~nfarm.report` (the notebook pipeline), :mod:`~nfarm.paths`.
"""

__version__ = "0.1.0"

from . import _allocator

_allocator.tune()   # batched kernels' speed must not depend on the caller's environment

from . import urdf as _urdf  # noqa: E402,F401 — registers the URDF reader with load_robot
