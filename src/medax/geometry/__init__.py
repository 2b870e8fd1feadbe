"""numpy-only geometry: curves, the 4-sided region, embeddings, B-spline fitting."""

from medax.geometry.arc import Arc
from medax.geometry.bspline import BSpline
from medax.geometry.curve import Closest, Curve
from medax.geometry.embedded_curve import EmbeddedCurve
from medax.geometry.embedding import Embedding, PlaneEmbedding
from medax.geometry.line import Line
from medax.geometry.polyline import Polyline
from medax.geometry.region import PAIRS, PairRoles, Region, pair_roles
from medax.geometry.region_io import (
    read_region,
    read_regions,
    region_from_dict,
    sample_regions_path,
)

__all__ = [
    "PAIRS",
    "Arc",
    "BSpline",
    "Closest",
    "Curve",
    "EmbeddedCurve",
    "Embedding",
    "Line",
    "PairRoles",
    "PlaneEmbedding",
    "Polyline",
    "Region",
    "pair_roles",
    "read_region",
    "read_regions",
    "region_from_dict",
    "sample_regions_path",
]
