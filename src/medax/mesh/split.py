"""The paper's recursion: split a region along its axis, again and again (``method="paper"``).

Splitting ``region`` along the axis of the pair ``(k, k+2)`` gives two regions of the same
kind: the axis end points cut ``B1`` at ``axis.t_start`` and ``B2`` at ``axis.t_end`` exactly
(``sub_curve``), and the axis spline becomes the side facing the other half. Each half keeps
the side numbering, so the same pair splits it again with the tracer unchanged.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

from medax import tolerances
from medax._progress import log_progress
from medax.axis import trace_axis
from medax.errors import InputError
from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve, sub_curve
from medax.geometry.region import Region, pair_roles

log = logging.getLogger(__name__)


#: samples per span of a traced axis used as a side, for the global closest-point search
AXIS_SIDE_SAMPLES = 6


class AxisSide(Curve):
    """A traced axis spline used as the side of a sub-region.

    Identical geometry (evaluation and derivatives delegate to the spline); only the sampling
    of the global closest-point search differs: the tracer's spline has one span per point
    (hundreds), short and nearly straight, so a few samples per span are enough, where the
    default 48 would make each distance query cost ``O(points x 48 spans)``. Every span is
    sampled: capping the total (12 pieces were used before) let the search return a local
    foot on a wiggly axis, 5e-5 of the diagonal farther than the nearest one."""

    samples_per_piece = AXIS_SIDE_SAMPLES

    def __init__(self, spline: Curve, pieces: int | None = None) -> None:
        self.spline = spline
        self.pieces = int(spline.complexity() if pieces is None else pieces)

    @property
    def dim(self) -> int:
        return self.spline.dim

    @property
    def kind(self) -> str:
        return "axis"

    def complexity(self) -> int:
        return self.pieces

    def breaks(self) -> FloatArray:
        return self.spline.breaks()

    def evaluate(self, t: FloatArray) -> FloatArray:
        return self.spline.evaluate(t)

    def derivative(self, t: FloatArray, order: int = 1) -> FloatArray:
        return self.spline.derivative(t, order)

    def reversed(self) -> Curve:
        return AxisSide(self.spline.reversed(), self.pieces)

    def transformed(self, offset: FloatArray, scale: float) -> Curve:
        return AxisSide(self.spline.transformed(offset, scale), self.pieces)


@dataclass(frozen=True)
class Piece:
    """A region cut out of the original one: ``b1``/``b2`` are the parameter ranges
    ``(t_lo, t_hi)`` of its start and end sides on the original ``B1`` and ``B2``."""

    region: Region
    b1: tuple[float, float]
    b2: tuple[float, float]


@dataclass(frozen=True)
class FamilyCurve:
    """One interior curve of a family: parameter-plane ``curve`` from ``B1`` to ``B2`` of the
    original region, meeting them at parameters ``t_b1`` and ``t_b2`` of those sides."""

    curve: Curve
    t_b1: float
    t_b2: float


def split_region(region: Region, pair: tuple[int, int], curve: Curve, t_start: float,
                 t_end: float) -> tuple[Region, Region]:  # fmt: skip
    """The two halves of ``region`` cut by ``curve`` (from ``B1(t_start)`` to ``B2(t_end)``):
    first the one along ``A1``, then the one along ``A2``. Same side numbering, CCW."""
    ro = pair_roles(pair)
    s = region.sides
    one: list[Curve] = [s[0], s[1], s[2], s[3]]
    two: list[Curve] = [s[0], s[1], s[2], s[3]]
    one[ro.b2] = sub_curve(s[ro.b2], 0.0, t_end)
    one[ro.a2] = curve.reversed()
    one[ro.b1] = sub_curve(s[ro.b1], t_start, 1.0)
    two[ro.a1] = curve
    two[ro.b2] = sub_curve(s[ro.b2], t_end, 1.0)
    two[ro.b1] = sub_curve(s[ro.b1], 0.0, t_start)
    # the halves inherit the embedding; their sides in space are E(side)
    r1 = Region((one[0], one[1], one[2], one[3]), region.embedding, f"{region.name}/1")
    r2 = Region((two[0], two[1], two[2], two[3]), region.embedding, f"{region.name}/2")
    return r1, r2


def _lerp(rng: tuple[float, float], t: float) -> float:
    return rng[0] + t * (rng[1] - rng[0])


def axis_family(
    region: Region,
    pair: tuple[int, int],
    divisions: int | None = None,
    size: float | None = None,
    tol: float = 1e-10,
    trace_method: str = "frame",
) -> list[FamilyCurve]:
    """Interior curves of one family, ordered from ``A1`` to ``A2``, by recursive splitting.

    With ``divisions = n`` a piece to be cut into ``n`` strips is split by the curve
    ``d1 / (d1 + d2) = floor(n/2) / n`` (the medial axis when ``n`` is even, so powers of two
    reproduce the paper exactly) and each half recursively. With ``size = h`` (the paper's
    rule) a piece is bisected along its medial axis until both its start and end sides are at
    most ``h`` long.
    """
    if (divisions is None) == (size is None):
        raise InputError("axis_family needs exactly one of divisions and size")
    ro = pair_roles(pair)
    out: list[FamilyCurve] = []

    def lengths(piece: Piece) -> float:
        r = piece.region
        return max(r.space_curve(ro.b1).length(), r.space_curve(ro.b2).length())

    def rec(piece: Piece, n: int | None, depth: int) -> None:
        if n is not None:
            if n <= 1:
                return
            k = n // 2
            ratio = k / n
        else:
            assert size is not None
            if lengths(piece) <= size * (1.0 + 1e-9) or depth > 30:
                return
            ratio = 0.5
        axis = trace_axis(piece.region, pair, tol=tol, method=trace_method, ratio=ratio,
                          point_tol=min(tolerances.POINT_TOL, tol))  # fmt: skip
        side = AxisSide(axis.spline)
        r1, r2 = split_region(piece.region, pair, side, axis.t_start, axis.t_end)
        t1, t2 = _lerp(piece.b1, axis.t_start), _lerp(piece.b2, axis.t_end)
        p1 = Piece(r1, (t1, piece.b1[1]), (piece.b2[0], t2))
        p2 = Piece(r2, (piece.b1[0], t1), (t2, piece.b2[1]))
        rec(p1, None if n is None else k, depth + 1)
        out.append(FamilyCurve(side, t1, t2))
        if divisions is not None:
            log_progress(log, f"{region.name} pair {pair}: split curves", len(out), divisions - 1)
        else:
            log.info("%s pair %s: split curve %d (depth %d)", region.name, pair, len(out), depth)
        rec(p2, None if n is None else n - k, depth + 1)

    rec(Piece(region, (0.0, 1.0), (0.0, 1.0)), divisions, 0)
    return out
