"""The CAD layer: the only package that imports OCP (OpenCASCADE).

Reading STEP/IGES/BRep (:mod:`medax.cad.reader`), topology maps and the tangency test
(:mod:`medax.cad.topology`), fillet classification (:mod:`medax.cad.classify`, data model
in :mod:`medax.cad.model`) and fillet faces as regions on their surfaces
(:mod:`medax.cad.face_region`).
"""

from medax.cad.model import (
    Classification,
    CornerRecord,
    Doubt,
    EdgeClass,
    EdgeInfo,
    FaceClass,
    FaceInfo,
    FilletRecord,
)

__all__ = [
    "Classification",
    "CornerRecord",
    "Doubt",
    "EdgeClass",
    "EdgeInfo",
    "FaceClass",
    "FaceInfo",
    "FilletRecord",
]
