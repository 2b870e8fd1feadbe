"""Fillet simplification (the paper's section 3, steps 3 to 5).

Split each fillet along its medial curve (:mod:`.medial`, :mod:`.split`), merge the halves
into their supporting faces on one exact surface (:mod:`.surfaces`), rebuild the solid on
shared edges (:mod:`.groups`, :mod:`.rebuild`) and validate it (:mod:`.validate`).
Entry point: :func:`simplify` with a :class:`BlendInput` built from a classification
(:func:`specs_from_classification`) or from known blend faces (:func:`specs_from_blend_faces`).
"""

from medax.cad.simplify.pipeline import FaceGroup, SimplifyResult, simplify
from medax.cad.simplify.specs import (
    BlendInput,
    FilletSpec,
    specs_from_blend_faces,
    specs_from_classification,
)

__all__ = [
    "BlendInput",
    "FaceGroup",
    "FilletSpec",
    "SimplifyResult",
    "simplify",
    "specs_from_blend_faces",
    "specs_from_classification",
]
