"""The URDF names in one import, where earlier versions defined them: :func:`to_urdf`
(:mod:`.urdf_export`), :func:`from_urdf` (:mod:`.urdf_import`) and :func:`urdf_outline` with its
records (:mod:`.urdf_tree`). Re-exports only; the library imports each from its own module.
"""

from __future__ import annotations

from .urdf_export import to_urdf
from .urdf_import import from_urdf
from .urdf_tree import URDFJoint, URDFOutline, urdf_outline

__all__ = ["to_urdf", "from_urdf", "urdf_outline", "URDFOutline", "URDFJoint"]
