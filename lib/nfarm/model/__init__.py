"""The arm's model: a DH chain and its parameters (:mod:`.robot`, read from YAML or from a URDF
by :mod:`.urdf_import`), rotations and pose errors (:mod:`.rotations`), forward kinematics and
Jacobians (:mod:`.kinematics`), recursive Newton–Euler dynamics (:mod:`.dynamics`), batched
small linear algebra (:mod:`.linalg`), and the same arm as a Pinocchio model, the independent
reference the tests check against (:mod:`.pinocchio_ref`).

URDF files: read and checked by :mod:`.urdf_parser`, their tree and outline :mod:`.urdf_tree`'s,
their chain's DH table extracted from its joint axes by :mod:`.dh_extraction`, the robot built by
:mod:`.urdf_import`; written by :mod:`.urdf_export` (:mod:`.urdf` re-exports the three names).

Imports only :mod:`nfarm.infra`.
"""

from . import urdf_import as _urdf_import  # noqa: E402,F401 — registers the URDF reader with load_robot
