"""The result of tracing a medial axis."""

from __future__ import annotations

from dataclasses import dataclass, field

from medax.geometry._types import FloatArray
from medax.geometry.bspline import BSpline
from medax.geometry.region import PairRoles, Region


@dataclass(frozen=True)
class WorkCounts:
    """How much work a trace took.

    Attributes
    ----------
    points : int
        Axis points returned.
    predictor_steps : int
        Predictor steps of the trace.
    corrector_iterations : int
        Corrector (Newton) iterations, over all points.
    distance_evaluations : int
        Evaluations of the distance field.
    refinements : int
        Rounds of refinement of the fitted spline.
    closed_form_pieces : int
        Conic pieces of a closed-form axis (two line-segment constraints); 0 when traced.
    """

    points: int = 0
    predictor_steps: int = 0
    corrector_iterations: int = 0
    distance_evaluations: int = 0
    refinements: int = 0
    closed_form_pieces: int = 0


@dataclass(frozen=True)
class MedialAxis:
    """The medial axis of a region between two constraint sides.

    The constraints are ``A1 = S[roles.a1]`` and ``A2 = S[roles.a2]``. Points are ordered
    from ``B1`` to ``B2``; the first lies on ``B1`` at parameter ``t_start`` of that side,
    the last on ``B2`` at ``t_end``. Lengths are in the region's unit.

    Attributes
    ----------
    region : Region
        The region ([Region][medax.geometry.region.Region]).
    pair : tuple of int
        The constraint sides, ``(0, 2)`` or ``(1, 3)``.
    roles : PairRoles
        The sides' roles ([PairRoles][medax.geometry.region.PairRoles]).
    method : str
        The method asked for, ``"frame"`` (also for a closed-form axis) or ``"paper"``.
    points : ndarray
        Axis points (n, 2) in the parameter plane.
    space_points : ndarray
        The points (n, dim) in space.
    foot1, foot2 : ndarray
        Foot points (n, dim) on A1 and A2, in space.
    d1, d2 : ndarray
        Distances (n,) to A1 and A2.
    spline : BSpline
        A B-spline in the parameter plane through the points.
    t_start, t_end : float
        Parameters of the end points on B1 and B2.
    max_point_error : float
        ``max |d1 - d2|`` over the points (absolute).
    max_curve_error : float
        The same measured on the spline 10x denser than the points (absolute).
    tol : float
        The curve tolerance asked for, relative to the diagonal.
    counts : WorkCounts
        How much work the trace took ([WorkCounts][medax.axis.result.WorkCounts]).
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
        """Number of axis points."""
        return int(self.points.shape[0])

    def __repr__(self) -> str:
        d = self.diagonal
        return (
            f"MedialAxis(region {self.region.name!r}, pair {self.pair[0]},{self.pair[1]}, "
            f"{self.method}, {self.n_points} points, max |d1-d2| {self.max_point_error / d:.2e} "
            f"(points) {self.max_curve_error / d:.2e} (spline) x diagonal {d:.5g})"
        )
