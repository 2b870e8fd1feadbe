"""The result of tracing a medial axis."""

from __future__ import annotations

from dataclasses import dataclass, field

from medax.geometry._types import FloatArray
from medax.geometry.bspline import BSpline
from medax.geometry.region import PairRoles, Region


@dataclass(frozen=True)
class WorkCounts:
    """How much work a trace took."""

    points: int = 0
    predictor_steps: int = 0
    corrector_iterations: int = 0
    distance_evaluations: int = 0
    refinements: int = 0
    #: conic pieces of a closed-form axis (two line-segment constraints); 0 when traced
    closed_form_pieces: int = 0


@dataclass(frozen=True)
class MedialAxis:
    """Medial axis of ``region`` between constraints ``A1 = S[roles.a1]``, ``A2 = S[roles.a2]``.

    Points are ordered from ``B1`` to ``B2``; the first lies on ``B1`` at parameter
    ``t_start`` of that side, the last on ``B2`` at ``t_end``.

    Arrays: ``points`` (n, 2) in the parameter plane, ``space_points`` (n, dim) in space,
    ``foot1``/``foot2`` (n, dim) foot points on A1/A2 in space, ``d1``/``d2`` (n,) distances.
    ``spline`` is a B-spline in the parameter plane through the points; ``max_point_error``
    is ``max |d1 - d2|`` over the points and ``max_curve_error`` the same measured on the
    spline 10x denser than the points (both absolute, in the region's length unit).
    """

    region: Region
    pair: tuple[int, int]
    roles: PairRoles
    method: str
    points: FloatArray
    space_points: FloatArray
    foot1: FloatArray
    foot2: FloatArray
    d1: FloatArray
    d2: FloatArray
    spline: BSpline
    t_start: float
    t_end: float
    max_point_error: float
    max_curve_error: float
    tol: float
    counts: WorkCounts = field(default_factory=WorkCounts)

    @property
    def diagonal(self) -> float:
        """The region's length scale (bounding-box diagonal in space)."""
        return self.region.diagonal

    @property
    def n_points(self) -> int:
        return int(self.points.shape[0])

    def __repr__(self) -> str:
        d = self.diagonal
        return (
            f"MedialAxis(region {self.region.name!r}, pair {self.pair[0]},{self.pair[1]}, "
            f"{self.method}, {self.n_points} points, max |d1-d2| {self.max_point_error / d:.2e} "
            f"(points) {self.max_curve_error / d:.2e} (spline) x diagonal {d:.5g})"
        )
