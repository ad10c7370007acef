"""nfarm — a reproducible study of a 5-DOF arm: DH kinematics, Levenberg–Marquardt inverse
kinematics, recursive Newton–Euler dynamics and ANFIS (Jang 1993).

The package is layered; each layer imports only the layers below it (``tests/test_layers.py``):

==================  ========================================================================
``infra``           the strict reader of user files, paths and atomic output, code digests,
                    time limits, headless notebook runs
``model``           the DH chain, rotations, kinematics, Newton–Euler dynamics, URDF, and the
                    Pinocchio model the tests check against
``solvers``         inverse kinematics (iterative and closed form), trajectories, tool paths,
                    workspace
``learning``        fuzzy partitions, ANFIS, learned IK and ID, feature bases, baselines
``presentation``    tables, figures, words for numbers, rerun recordings
``study``           study files and data sets, sweep jobs and sweeps, statistics, the summary
``publishing``      the report pipeline and its pages, the course edition, the arm panel
==================  ========================================================================

The names users and notebooks need most are importable from the top (``from nfarm import fk,
rnea, LearnedIK``, ``nfarm.ik.solve``, ``nfarm.ik.closed_form``); they are loaded on first use,
so ``import nfarm`` stays light and a cache key (:mod:`nfarm.infra.provenance`) holds only the
modules a notebook's names come from (:data:`PUBLIC`).

>>> import nfarm
>>> from nfarm.infra.paths import PARAMS
>>> robot = nfarm.load_robot(PARAMS / "robots" / "intelbot5.yaml")
>>> T_0e = nfarm.fk(robot, [0.0, 0.0, 0.0, 0.0, 0.0])     # the zero configuration
>>> T_0e.shape
(4, 4)
"""

from __future__ import annotations

import importlib
import sys
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

from .infra import _allocator

_allocator.tune()   # batched kernels' speed must not depend on the caller's environment

#: Public names importable from the top: name → the module (dotted from the package) defining
#: it; a name equal to the module's last part is the module itself (``nfarm.ik``).
PUBLIC: dict[str, str] = {
    **dict.fromkeys(["Robot", "load_robot", "robot_hash", "sample_configurations", "ParamsError",
                     "ParamsWarning"], "model.robot"),
    **dict.fromkeys(["fk", "fk_all", "jacobian", "manipulability", "min_singular_value"],
                    "model.kinematics"),
    **dict.fromkeys(["rnea", "mass_matrix", "coriolis", "gravity_torques", "regressor",
                     "joint_drive_torques"], "model.dynamics"),
    **dict.fromkeys(["pose_error", "matrix_to_quat", "quat_to_matrix", "matrix_to_rpy",
                     "rpy_to_matrix"], "model.rotations"),
    "to_urdf": "model.urdf_export",
    "from_urdf": "model.urdf_import",
    "ik": "solvers.ik",
    **dict.fromkeys(["LM", "DLS", "Pinv", "JT"], "solvers.ik"),
    **dict.fromkeys(["closed_form"], "solvers.geometric_ik"),
    **dict.fromkeys(["Trajectory", "cubic", "quintic", "via_points"], "solvers.trajectory"),
    **dict.fromkeys(["ANFIS"], "learning.anfis"),
    **dict.fromkeys(["LearnedIK", "OutsideTrainingWarning"], "learning.learned"),
    "LearnedID": "learning.learned_id",
    **dict.fromkeys(["BaselineID"], "learning.baselines"),
    "load_study": "study.study_files",
    "build_datasets": "study.datasets",
}

__all__ = sorted(PUBLIC)


class _ModuleAliases:
    """``import nfarm.ik`` (and ``from nfarm.ik import solve``): a public name that is a module
    (``PUBLIC``'s ``ik``) imports as that module itself, loaded on first use; its own
    ``__spec__`` is kept (the alias only names it)."""

    @staticmethod
    def _target(fullname: str) -> str | None:
        prefix, _, short = fullname.rpartition(".")
        where = PUBLIC.get(short)
        if prefix == __name__ and where and where.rsplit(".", 1)[-1] == short and where != short:
            return f"{__name__}.{where}"
        return None

    def find_spec(self, fullname: str, path=None, target=None):
        import importlib.util

        return importlib.util.spec_from_loader(fullname, self) if self._target(fullname) else None

    def create_module(self, spec):
        module = importlib.import_module(self._target(spec.name))
        self._spec = module.__spec__           # the import system's bookkeeping overwrites it
        return module

    def exec_module(self, module) -> None:
        module.__spec__ = self._spec


if not any(isinstance(finder, _ModuleAliases) for finder in sys.meta_path):
    sys.meta_path.append(_ModuleAliases())


def __getattr__(name: str) -> Any:
    """A public name, imported from its module on first use (PEP 562)."""
    where = PUBLIC.get(name)
    if where is None:
        raise AttributeError(f"module 'nfarm' has no attribute {name!r}")
    module = importlib.import_module(f".{where}", __name__)
    value = module if where.rsplit(".", 1)[-1] == name else getattr(module, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *PUBLIC})


if TYPE_CHECKING:   # for readers and type checkers; at run time the names come from __getattr__
    from .learning.anfis import ANFIS
    from .learning.baselines import BaselineID
    from .learning.learned import LearnedIK, OutsideTrainingWarning
    from .learning.learned_id import LearnedID
    from .model.dynamics import coriolis, gravity_torques, joint_drive_torques, mass_matrix, regressor, rnea
    from .model.kinematics import fk, fk_all, jacobian, manipulability, min_singular_value
    from .model.robot import ParamsError, ParamsWarning, Robot, load_robot, robot_hash, sample_configurations
    from .model.rotations import matrix_to_quat, matrix_to_rpy, pose_error, quat_to_matrix, rpy_to_matrix
    from .model.urdf_export import to_urdf
    from .model.urdf_import import from_urdf
    from .solvers import ik
    from .solvers.ik import DLS, JT, LM, Pinv
    from .solvers.geometric_ik import closed_form
    from .solvers.trajectory import Trajectory, cubic, quintic, via_points
    from .study.datasets import build_datasets
    from .study.study_files import load_study
