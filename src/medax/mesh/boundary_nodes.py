"""Boundary nodes of the ratio grid: where they lie on each side, and the ratio there.

Two rules (:data:`RULES`):

- ``"arclength"`` (default): equal arc length in space along each side, as gmsh's
  transfinite curves; the ratio of the crossing pair is measured at each node.
- ``"ratio"``: the end points of the curves of constant ratio ``k / n`` (the root of one
  equation along the side, :func:`side_nodes`); the ratios are then those constants.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np

from medax.errors import MeshError
from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve
from medax.geometry.embedded_curve import EmbeddedCurve
from medax.geometry.region import Region
from medax.mesh.arclength import arclength_params
from medax.mesh.ratio_field import (
    PlanarField,
    SideDistances,
    angular_ratio,
    evaluate_field,
    foot_angle,
    pair_weighting,
)

log = logging.getLogger(__name__)
RULES = ("arclength", "ratio")
_SCAN = 513  # samples per side when bracketing boundary nodes
# side k carries the end points of the curves of the pair (a, b) (index into the kinds)
_SIDE_PAIRS = ((0, 1, 3, 1), (1, 0, 2, 0), (2, 1, 3, 1), (3, 0, 2, 0))


def side_params(
    region: Region,
    levels: list[tuple[int, int]],
    tol: float,
    kinds: tuple[str, str],
    rule: str = "arclength",
    fractions: Sequence[FloatArray] | None = None,
) -> list[list[tuple[FloatArray, FloatArray]]]:
    """Per level ``(n1, n2)``, per side, the parameters (in the side's direction) of the
    boundary nodes and the ratio of the crossing pair at them (each (n + 1,)); the nodes of
    all levels on one side are found together. ``fractions`` (rule ``"arclength"``, one
    level only): per side the arc-length fractions (n + 1,) of its nodes, increasing from 0
    to 1, instead of ``k / n``."""
    out: list[list[tuple[FloatArray, FloatArray]]] = [[] for _ in levels]
    if fractions is not None and (rule != "arclength" or len(levels) != 1):
        raise ValueError("boundary fractions need the arclength rule and one level")
    for side, a, b, kind in _SIDE_PAIRS:
        counts = [lev[side % 2] for lev in levels]
        if fractions is not None:
            fr = np.asarray(fractions[side], dtype=np.float64)
            if fr.shape != (counts[0] + 1,) or fr[0] != 0.0 or fr[-1] != 1.0:
                raise ValueError(
                    f"side {side}: fractions must run from 0 to 1 in {counts[0]} steps"
                )
        else:
            fr = np.concatenate([np.arange(n + 1) / n for n in counts])
        if rule == "arclength":
            curve = region.sides[side]
            if not region.embedding.is_identity:
                curve = EmbeddedCurve(curve, region.embedding)
            # levels share most fractions (halved counts): each one measured once
            uniq, back = np.unique(fr, return_inverse=True)
            tu = arclength_params(curve, uniq)
            ru = side_ratios(region, region.sides[side].evaluate(tu), a, b, kinds[kind])
            t, r = tu[back], ru[back]
        else:
            r = 1.0 - fr if side in (0, 3) else fr  # (ratio 1 at S3's end of S0, at S2's of S3)
            t = side_nodes(region, side, a, b, r, tol, kinds[kind])
        cuts = np.cumsum([n + 1 for n in counts])[:-1]
        for lev, (tp, rp) in enumerate(zip(np.split(t, cuts), np.split(r, cuts), strict=True)):
            rp[[0, -1]] = np.round(rp[[0, -1]])  # (the side's ends lie on a or on b)
            out[lev].append((tp, rp))
    return out


def side_ratios(region: Region, p: FloatArray, a: int, b: int, weighting: str) -> FloatArray:
    """The ratio (n,) of the pair ``(a, b)`` at parameter points ``p`` (n, 2)."""
    sides = SideDistances(region, 0, (weighting, weighting))
    x = region.embedding.evaluate(p)
    da, ua, _ = sides.dist(a, x, None)
    db, ub, _ = sides.dist(b, x, None)
    return angular_ratio(da, db, foot_angle(ua, ub, weighting))


def side_nodes(
    region: Region,
    side: int,
    a: int,
    b: int,
    ratios: FloatArray,
    tol: float,
    weighting: str = "auto",
) -> FloatArray:
    """Parameters ``t`` (len(ratios),) on ``side`` where the ratio curve of ``(a, b)`` ends.

    Ratios 0 and 1 are the side's end points on ``a`` and on ``b``. Each ratio is bracketed
    on a scan of the side (the first sign change from the ``a`` end) and solved by the
    Illinois variant of regula falsi, all ratios at once, to ``|t1 - t0| <= 4e-16``.
    """
    curve: Curve = region.sides[side]
    weighting = pair_weighting(region, a, b, weighting)
    sides = SideDistances(region, 0, (weighting, weighting))
    r = np.asarray(ratios, dtype=np.float64)
    s = np.linspace(0.0, 1.0, _SCAN)
    x = region.embedding.evaluate(curve.evaluate(s))
    da, ua, _ = sides.dist(a, x, None)
    db, ub, _ = sides.dist(b, x, None)
    phi = angular_ratio(da, db, foot_angle(ua, ub, weighting))
    # orient the scan so that phi runs from the a end (0) to the b end (1)
    if phi[0] > phi[-1]:
        s, phi = s[::-1], phi[::-1]
    out = np.empty(r.size)
    inner = (r > 0.0) & (r < 1.0)
    out[r <= 0.0] = s[0]
    out[r >= 1.0] = s[-1]
    ri = r[inner]
    if ri.size == 0:
        return out
    above = phi[None, :] >= ri[:, None]  # (k, scan)
    first = np.argmax(above, axis=1)
    if np.any(~above.any(axis=1)) or np.any(first == 0):
        raise MeshError(
            f"region '{region.name}': a ratio curve of sides ({a}, {b}) does not meet side {side}"
        )
    if np.any(np.diff(phi) < -1e-12):
        log.warning("region '%s': the ratio is not monotone along side %d", region.name, side)
    lo, hi = s[first - 1], s[first]

    pair = 0 if a == 0 else 1
    kinds = (weighting, "distance") if pair == 0 else ("distance", weighting)
    planar = PlanarField(region, kinds) if PlanarField.supports(region, kinds) else None
    w = planar.weights(pair, ri) if planar is not None else ()

    def f(t: FloatArray) -> FloatArray:
        """``g`` on the side: the sign of ``phi - r``."""
        p = curve.evaluate(t)
        if planar is not None:  # (only the pair (a, b) is evaluated)
            return planar.value(pair, p[:, 0].copy(), p[:, 1].copy(), w)
        return evaluate_field(sides, a, b, ri, p, weighting)[0]

    flo, fhi = f(lo), f(hi)
    moved = np.zeros(ri.size, dtype=np.int8)  # -1: lo moved last, +1: hi moved last
    for _ in range(100):
        den = fhi - flo
        t = np.where(den != 0.0, lo - flo * (hi - lo) / np.where(den != 0.0, den, 1.0), lo)
        t = np.clip(t, np.minimum(lo, hi), np.maximum(lo, hi))
        ft = f(t)
        left = ft < 0.0
        # Illinois: halve the value kept at an end that stays put twice in a row
        fhi = np.where(left & (moved == -1), 0.5 * fhi, fhi)
        flo = np.where(~left & (moved == 1), 0.5 * flo, flo)
        lo, flo = np.where(left, t, lo), np.where(left, ft, flo)
        hi, fhi = np.where(left, hi, t), np.where(left, fhi, ft)
        moved = np.where(left, -1, 1).astype(np.int8)
        if np.all((np.abs(hi - lo) <= 4e-16) | (np.abs(ft) <= 1e-3 * tol)):
            break
    out[inner] = np.where(np.abs(flo) <= np.abs(fhi), lo, hi)
    return out
