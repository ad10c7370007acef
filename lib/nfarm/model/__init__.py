"""The arm's model: a DH chain and its parameters (:mod:`.robot`, read from YAML or from a URDF
by :mod:`.urdf`), rotations and pose errors (:mod:`.rotations`), forward kinematics and
Jacobians (:mod:`.kinematics`), recursive Newton–Euler dynamics (:mod:`.dynamics`), batched
small linear algebra (:mod:`.linalg`), and the same arm as a Pinocchio model, the independent
reference the tests check against (:mod:`.pinocchio_ref`).

Imports only :mod:`nfarm.infra`.
"""

from . import urdf as _urdf  # noqa: E402,F401 — registers the URDF reader with load_robot
