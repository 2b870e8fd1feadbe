"""An exact surface for a planar face merged with fillet halves along two perpendicular
directions and the sphere corners where they meet (a face of a box with rounded edges, or
a pocket's floor and walls: concave).

In a frame ``(o, ex, ey, n)`` on the supporting plane (coordinates ``X, Y, Z``) every fillet
half is a cylinder of radius ``r`` along ``ey`` (an x-strip, tangent to the plane on the line
``X = a``) or along ``ex`` (a y-strip, ``Y = b``) whose axis lies at ``Z = -rho``
(``rho = +r`` when it lies below the plane, ``-r`` above), and every corner piece is a sphere
of radius ``r`` centred at ``(a, b, -rho)``. With the x-profile ``(x, zx)`` (an arc at each
strip, a line between them) and the y-profile ``(y, zy)`` alike, the surface

    P = (x, y + zx g / rho, zx + zy + zx zy / rho),

``g = y - b`` on a y-strip's arc and a cubic on the line that is 0 at its ends and leaves
them at the slope of ``y``, is the plane where both profiles are flat, a strip's cylinder
where one is, and in a corner cell the sphere
(``(X - a, Y - b, Z + rho) = (r sin t, r cos t sin p, rho cos t cos p)`` up to the sides'
signs). Each term is a product of a function of ``x``'s parameter and one of ``y``'s with
the denominator ``w_x w_y``, so ``P`` is one tensor-product rational B-spline whose poles
follow the same formula from the profiles' control values and whose weights are the
products of theirs. Each profile is a C1 rational cubic (:func:`_profile`), so the surface
is C1 in its parameters (the mesher measures lengths along its curves by Gauss rules, which
a jump of the parametric speed at a knot line spoils): 8 x 8 poles for a face with a strip
on every side, where the height-field fit (:mod:`.fitted`) needs about 34 x 34 to reach its
tolerance. The B-spline's ``u`` runs along ``y``, its ``v`` along ``x``.

Every member's samples (edges and inside) are checked against the closed form and the
B-spline against it at samples of every span; anything else (other surfaces, strips not
along two perpendicular directions, unequal radii, a mitre where the strips meet) returns
the reason and the caller fits the face.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.GeomAbs import GeomAbs_Cylinder, GeomAbs_Plane, GeomAbs_Sphere

from medax.cad.simplify.fitted import FittedSurface
from medax.cad.simplify.occ import Array, edge_points, edges_of, xyz

#: The surface kind of a merged face on this route (the face groups' ``surface``).
ROUNDED = "rounded"
#: The arcs run past the farthest member sample by this angle (rad), as the exact routes'
#: half-arcs run past the medial curve (:data:`.surfaces.MEDIAL_OVERSHOOT`).
OVERSHOOT = 0.05
#: Largest arc angle (rad): a strip reaching steeper is no graph over the plane.
MAX_ARC = math.radians(80.0)
#: A side without a strip: the line runs past the members by this share of their extent.
FREE_END = 0.1
#: Samples per edge and per direction inside each member for the closed-form check.
EDGE_SAMPLES, FACE_SAMPLES = 9, 5


@dataclass(frozen=True)
class RoundedSurface(FittedSurface):
    """A :class:`.fitted.FittedSurface` that is exact (this route's): the face is validated
    as the exact surfaces are, and its kind is :data:`ROUNDED`."""


def rounded_surface(plane_face: Any, members: Sequence[Any], tol: float) -> RoundedSurface | str:
    """The exact surface of the merged face made of ``members`` (faces of the split solid:
    pieces of the plane of ``plane_face``, cylinder halves, sphere corner pieces), as a
    :class:`RoundedSurface` with its measured ``error`` (largest distance of the
    members' samples and of the B-spline's own samples from the closed form, length unit)
    and no volume change; the reason (str) when the members are not such a face or a
    sample is farther than ``tol`` (length unit)."""
    from medax.cad.simplify.validate import face_samples

    ad = BRepAdaptor_Surface(plane_face)
    if ad.GetType() != GeomAbs_Plane:
        return "the rounded-box route takes a planar supporting face only"
    pl = ad.Plane()
    o, n = xyz(pl.Location()), xyz(pl.Axis().Direction())
    kinds: list[tuple[str, Array, Array, float]] = []  # (kind, point, direction, radius)
    for f in members:
        sa = BRepAdaptor_Surface(f)
        k = sa.GetType()
        if k == GeomAbs_Plane:
            ax = sa.Plane().Axis()
            kinds.append(("plane", xyz(ax.Location()), xyz(ax.Direction()), 0.0))
        elif k == GeomAbs_Cylinder:
            c = sa.Cylinder()
            ax = c.Axis()
            kinds.append(("cylinder", xyz(ax.Location()), xyz(ax.Direction()), c.Radius()))
        elif k == GeomAbs_Sphere:
            sph = sa.Sphere()
            kinds.append(("sphere", xyz(sph.Location()), np.zeros(3), sph.Radius()))
        else:
            return "the rounded-box route takes plane, cylinder and sphere pieces only"
    cyls = [i for i, k in enumerate(kinds) if k[0] == "cylinder"]
    if not cyls:
        return "no cylinder piece"
    for kind, p, d, _ in kinds:
        if kind == "plane" and (np.linalg.norm(np.cross(d, n)) > 1e-9 or abs((p - o) @ n) > tol):
            return "a plane piece off the supporting plane"
    ey = kinds[cyls[0]][2]
    if abs(ey @ n) > 1e-9:
        return "a cylinder piece not parallel to the plane"
    ey = ey - (ey @ n) * n
    ey /= np.linalg.norm(ey)
    ex = np.cross(ey, n)
    radii = [k[3] for k in kinds if k[0] != "plane"]
    r = radii[0]
    heights = [(k[1] - o) @ n for k in kinds if k[0] != "plane"]
    if max(radii) - min(radii) > tol or max(heights) - min(heights) > tol:
        return "pieces of unequal radii or axis heights"
    rho = -float(np.mean(heights))
    if abs(abs(rho) - r) > tol:
        return "a cylinder piece not tangent to the plane"
    axes: dict[int, int] = {}
    for i in cyls:
        d = kinds[i][2]
        axes[i] = 0 if abs(abs(d @ ey) - 1) <= 1e-9 else 1 if abs(abs(d @ ex) - 1) <= 1e-9 else -1
        if axes[i] < 0:
            return "fillet pieces not along two perpendicular directions"
    pts = [
        np.vstack(
            [*(edge_points(e, EDGE_SAMPLES) for e in edges_of(f)), face_samples(f, FACE_SAMPLES)]
        )
        for f in members
    ]
    local = [np.column_stack([(q - o) @ ex, (q - o) @ ey, (q - o) @ n]) for q in pts]
    # the strips: (axis, side) -> tangency coordinate
    strips: dict[tuple[int, int], float] = {}
    for i in cyls:
        p, axis = kinds[i][1], axes[i]
        at = float((p - o) @ (ex if axis == 0 else ey))
        off = float(np.mean(local[i][:, axis]) - at)
        if abs(off) <= tol:
            return "a cylinder piece on both sides of its axis"
        key = (axis, 1 if off > 0 else -1)
        if key in strips and abs(strips[key] - at) > tol:
            return "two fillets on one side of the face"
        strips[key] = at
    for axis in (0, 1):
        if (axis, -1) in strips and (axis, 1) in strips and strips[axis, -1] >= strips[axis, 1]:
            return "crossing fillet strips"
    for k in kinds:  # a sphere corner sits where two strips meet
        if k[0] == "sphere":
            c = k[1] - o
            if not any(
                abs(c @ ex - a) <= tol for (ax, _), a in strips.items() if ax == 0
            ) or not any(abs(c @ ey - b) <= tol for (ax, _), b in strips.items() if ax == 1):
                return "a sphere piece off the strips' corners"
    allp = np.vstack(local)
    over = _over(allp, strips)
    ext: dict[tuple[int, int], float] = {}  # the arc angle of each strip
    profiles = []
    for axis in (0, 1):
        ends: list[tuple[float, float] | None] = []  # (tangency, arc angle) per side
        for side in (-1, 1):
            if (axis, side) not in strips:
                ends.append(None)
                continue
            at = strips[axis, side]
            beyond = side * (allp[:, axis] - at) > 0
            reach = float(_angles(allp, over, rho, r, axis)[beyond].max(initial=0.0))
            if reach > MAX_ARC - OVERSHOOT:
                return "a fillet piece too steep over the plane"
            ext[axis, side] = reach + OVERSHOOT
            ends.append((at, ext[axis, side]))
        lo_x, hi_x = float(allp[:, axis].min()), float(allp[:, axis].max())
        pad = FREE_END * max(hi_x - lo_x, tol)
        lo = ends[0][0] if ends[0] else lo_x - pad
        hi = ends[1][0] if ends[1] else hi_x + pad
        if not hi > lo:
            return "no flat part between the fillet strips"
        profiles.append(_profile(lo, hi, ends[0], ends[1], r, rho))
    (cx, zx, wx, _, kx, mx), (cy, zy, wy, gy, ky, my) = profiles
    zxx, zyy = np.meshgrid(zx, zy, indexing="ij")
    X = np.repeat(cx[:, None], len(cy), axis=1)
    Y = cy[None, :] + zxx * gy[None, :] / rho
    Z = zxx + zyy + zxx * zyy / rho
    # u along y (the profile the sphere terms couple to x), v along x: OCCT's default
    # integrator (Gauss along u from the boundary) is then as close as on the fitted faces
    # (12-fillet box -1.0e-4 of the volume; -2.0e-4 the other way round)
    surface = _bspline(o, ex, ey, n, X.T, Y.T, Z.T, np.outer(wy, wx), (ky, my), (kx, mx))
    limits = (cx[0], cx[-1], cy[0], cy[-1])
    err = max(float(_model_error(q, strips, ext, limits, r, rho).max()) for q in local)
    frame = (o, ex, ey, n)
    err = max(err, _surface_error(surface, frame, (ky, kx), strips, ext, limits, r, rho))
    if not err <= tol:
        return f"the pieces are {err:.1e} off a rounded box's face (sphere corners, equal radii)"
    return RoundedSurface(surface, err, 0.0, 0.0)


def _profile(
    lo: float,
    hi: float,
    low: tuple[float, float] | None,
    high: tuple[float, float] | None,
    r: float,
    rho: float,
) -> tuple[Array, Array, Array, Array, Array, Array]:
    """Control values of one direction's profile, a C1 rational cubic (arc - line - arc):
    coordinates, heights, weights and ``g`` (coordinate - tangency on the arcs; on the line
    ``L s (1 - s) (1 - 2 s)``, which leaves the line at the slope of the coordinate itself at
    both ends, so the surface's ``y + zx g / rho`` is C1 across the tangency lines), each
    (3 spans + 1,), then the knots (at the spans' parameter lengths) and their
    multiplicities (double inside).

    Each arc is the rational quadratic with weights 1 at its middle control point (the
    tangents' intersection) and at the tangency and ``1 / cos^2(a / 2)`` at its far end
    (``a`` its angle; a circle still, reparametrised so the weight's slope is 0 where the
    line begins), over a parameter length ``2 r tan(a / 2)`` and the line over its own length:
    the coordinate's slope is 1 on both sides of each tangency. Arcs are raised to degree 3."""
    spans: list[tuple[Array, float]] = []  # homogeneous Bezier points (4, 4): w c, w z, w g, w

    def arc(at: float, side: int, angle: float) -> None:
        h = 0.5 * angle
        far = (at + side * r * math.sin(angle), -rho + rho * math.cos(angle))
        mid = (at + side * r * math.tan(h), 0.0)  # where the tangents at both ends meet
        cart = [far, mid, (at, 0.0)]
        w = [1.0 / math.cos(h) ** 2, 1.0, 1.0]
        quad = np.array(
            [[w[k] * c, w[k] * z, w[k] * (c - at), w[k]] for k, (c, z) in enumerate(cart)]
        )
        if side > 0:
            quad = quad[::-1]
        cubic = np.array(
            [quad[0], (quad[0] + 2 * quad[1]) / 3, (2 * quad[1] + quad[2]) / 3, quad[2]]
        )
        spans.append((cubic, 2 * r * math.tan(h)))

    if low is not None:
        arc(low[0], -1, low[1])
    length = hi - lo
    line = np.array(
        [[lo + k * length / 3, 0.0, length * g, 1.0] for k, g in enumerate((0, 1 / 3, -1 / 3, 0))]
    )
    spans.append((line, length))
    if high is not None:
        arc(high[0], 1, high[1])
    # double knots: the junction points (between their neighbours, as C1 asks) drop out
    rows = np.vstack([spans[0][0][:3]] + [sp[0][1:3] for sp in spans[1:]] + [spans[-1][0][3:]])
    w = rows[:, 3]
    knots = np.cumsum([0.0] + [sp[1] for sp in spans])
    mults = np.array([4] + [2] * (len(spans) - 1) + [4])
    return rows[:, 0] / w, rows[:, 1] / w, w, rows[:, 2] / w, knots, mults


def _over(q: Array, strips: dict[tuple[int, int], float]) -> Array:
    """How far local points ``q`` (k, 3) lie beyond the strips' tangency lines, (k, 2)."""
    over = np.zeros((len(q), 2))
    for (axis, side), at in strips.items():
        over[:, axis] += np.maximum(side * (q[:, axis] - at), 0.0)
    return over


def _angles(q: Array, over: Array, rho: float, r: float, axis: int) -> Array:
    """The profile angle (rad) of local points ``q`` (k, 3) beyond a strip of ``axis``:
    ``asin`` of the distance past the tangency line over ``r`` across the x-strips (so also in
    the corner cells), the angle about the x-direction across the y-strips (k,)."""
    if axis == 0:
        return np.arcsin(np.clip(over[:, 0] / r, 0.0, 1.0))
    return np.arctan2(over[:, 1], np.sign(rho) * (q[:, 2] + rho))


def _model_error(
    q: Array,
    strips: dict[tuple[int, int], float],
    ext: dict[tuple[int, int], float],
    limits: tuple[float, float, float, float],
    r: float,
    rho: float,
) -> Array:
    """Distance (k,) of local points ``q`` (k, 3) from the closed form: the plane between
    the strips, a strip's cylinder, a corner's sphere; inf where the point lies beyond the
    surface's ends (``limits``: x and y range; ``ext``: each strip's arc angle) or on the far
    half of a cylinder or sphere."""
    over = _over(q, strips)
    outside = (q[:, 0] < limits[0] - 1e-9 * r) | (q[:, 0] > limits[1] + 1e-9 * r)
    outside |= (q[:, 1] < limits[2] - 1e-9 * r) | (q[:, 1] > limits[3] + 1e-9 * r)
    for (axis, side), t in ext.items():
        beyond = side * (q[:, axis] - strips[axis, side]) > 0
        outside |= beyond & (_angles(q, over, rho, r, axis) > t + 1e-9)
    dz = q[:, 2] + rho  # from the axes' height
    far = np.sign(rho) * dz < 0
    err = np.abs(np.sqrt(over[:, 0] ** 2 + over[:, 1] ** 2 + dz**2) - r)
    return np.where(outside | far, np.inf, err)


def _surface_error(
    surface: Any,
    frame: tuple[Array, Array, Array, Array],
    knots: tuple[Array, Array],
    strips: dict[tuple[int, int], float],
    ext: dict[tuple[int, int], float],
    limits: tuple[float, float, float, float],
    r: float,
    rho: float,
    per_span: int = 5,
) -> float:
    """Largest distance of the B-spline's points (``per_span`` per span and direction) from
    the closed form."""
    o, ex, ey, n = frame
    us, vs = (
        np.unique(
            np.concatenate(
                [np.linspace(a, b, per_span) for a, b in zip(k[:-1], k[1:], strict=True)]
            )
        )
        for k in knots
    )
    pts = np.array([xyz(surface.Value(float(u), float(v))) for u in us for v in vs]) - o
    q = np.column_stack([pts @ ex, pts @ ey, pts @ n])
    return float(_model_error(q, strips, ext, limits, r, rho).max())


def _bspline(
    o: Array,
    ex: Array,
    ey: Array,
    n: Array,
    X: Array,
    Y: Array,
    Z: Array,
    W: Array,
    u: tuple[Array, Array],
    v: tuple[Array, Array],
) -> Any:
    """``Geom_BSplineSurface`` of degree 3 with poles ``o + X ex + Y ey + Z n`` and weights
    ``W`` (each (nu, nv)), knots and multiplicities ``u`` and ``v``."""
    from OCP.collections import Array1_double, Array1_int, Array2_double, Array2_gp_Pnt
    from OCP.Geom import Geom_BSplineSurface
    from OCP.gp import gp_Pnt

    nu, nv = X.shape
    poles, weights = Array2_gp_Pnt(1, nu, 1, nv), Array2_double(1, nu, 1, nv)
    world = o + X[..., None] * ex + Y[..., None] * ey + Z[..., None] * n
    for i in range(nu):
        for j in range(nv):
            poles.SetValue(i + 1, j + 1, gp_Pnt(*map(float, world[i, j])))
            weights.SetValue(i + 1, j + 1, float(W[i, j]))

    def arrays(k: Array, m: Array) -> tuple[Any, Any]:
        ak, am = Array1_double(1, len(k)), Array1_int(1, len(k))
        for i, (kv, mv) in enumerate(zip(k, m, strict=True)):
            ak.SetValue(i + 1, float(kv))
            am.SetValue(i + 1, int(mv))
        return ak, am

    uk, um = arrays(*u)
    vk, vm = arrays(*v)
    return Geom_BSplineSurface(poles, weights, uk, vk, um, vm, 3, 3)
