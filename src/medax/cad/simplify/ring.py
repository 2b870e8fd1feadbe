"""A fitted surface for a supporting plane or cylinder merged with a blend half that runs
all the way round it (a fillet around a boss or a hole): the *ring* route.

The merged face is parametrised in ring coordinates ``(theta, sigma)`` around the
contact curve (:mod:`medax.geometry.ring_heights`): ``theta`` round the axis, ``sigma``
from the contact curve into the support (> 0) or over the blend (< 0). Its points are
known exactly: on the support in closed form, over the blend where the ray meets the
blend's NURBS copy. The three coordinates are fitted together by a cubic B-spline,
periodic in ``theta`` and with a C1 double knot at ``sigma = 0``
(:func:`medax.geometry.periodic_fit.fit_radial_height`): the curvature jump along the
contact curve lies on that knot line, so the fit keeps converging (6 - 9x per halving on
the slanted boss; the planar height field over its plate put the jump across the knots
and stalled at 2.8e-4). On the support the points are linear in ``sigma`` (one span
there); on a plane they are fitted in the plane's frame with the height off it held at
zero there, so the plane stays exactly plane. The error is measured on a check grid (7
points per span, the Euclidean distance to the exact points) and must be within the
tolerance; the surface is an OCCT ``Geom_BSplineSurface`` periodic in ``u``. A plane inside
the contact curve (a boss top) is refused: the polar frame's pole would be on the face.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.GeomAbs import GeomAbs_BSplineSurface, GeomAbs_Cylinder, GeomAbs_Plane
from scipy.interpolate import CubicSpline

from medax.cad.face_region import surface_embedding
from medax.cad.simplify.fitted import FittedSurface
from medax.cad.simplify.occ import (
    Array,
    edge_points,
    edges_of,
    face_inside_point,
    face_normal_at,
    uv_bounds,
    xyz,
)
from medax.geometry.periodic_fit import PERIOD, PeriodicFit, fit_radial_height, periodic_knots
from medax.geometry.ring_heights import RingFrame, goes_round, ray_points
from medax.geometry.surfaces import NurbsSurface
from medax.geometry.tensor_fit import CHECK_PER_SPAN, DEGREE, span_samples

#: Samples per contact / medial edge.
CURVE_SAMPLES = 720
#: The blend's data are taken this share of the half's width beyond the medial curve (the
#: fit sees the blend continue there, so the medial curve is no edge of the data).
BEYOND_MEDIAL = 0.1
#: Spacing of the first level, as a share of the half's smallest width; halvings at most.
FIRST_SPACING, LEVELS = 0.5, 5
#: A cylinder's second blend half is taken when its contact curve lies on a line ``sigma =
#: const`` of the first half's frame to within this share of its width.
PARALLEL_SHARE = 0.01
#: How a refusal begins when the group is no ring at all (another route's business).
NOT_A_RING = "not a ring: "


def _shared_edges(a: Any, b: Any) -> list[Any]:
    """Edges of face ``a`` that are also edges of face ``b`` (seams and degenerated
    edges left out)."""
    eb = list(edges_of(b))
    out: list[Any] = []
    for e in edges_of(a):
        if BRep_Tool.Degenerated_s(e) or BRep_Tool.IsClosed_s(e, a):
            continue
        if any(e.IsSame(f) for f in eb):
            if not any(e.IsSame(g) for g in out):
                out.append(e)
    return out


def _loop_samples(edges: Sequence[Any], n: int) -> Array | None:
    """Samples (k, 3) along the closed chain of ``edges`` in order (the first point not
    repeated), None when they do not chain into one closed loop."""
    parts = [edge_points(e, n) for e in edges]
    if not parts:
        return None
    scale = max(float(np.ptp(np.vstack(parts), axis=0).max()), 1e-300)
    tol = 1e-7 * scale
    chain = [parts.pop(0)]
    while parts:
        end = chain[-1][-1]
        for i, p in enumerate(parts):
            if np.linalg.norm(p[0] - end) <= tol:
                chain.append(parts.pop(i))
                break
            if np.linalg.norm(p[-1] - end) <= tol:
                chain.append(parts.pop(i)[::-1])
                break
        else:
            return None
    if np.linalg.norm(chain[-1][-1] - chain[0][0]) > tol:
        return None
    return np.vstack([c[:-1] for c in chain])


def _periodic_spline(theta: Array, values: Array) -> CubicSpline:
    order = np.argsort(theta)
    t, v = theta[order], values[order]
    keep = np.concatenate([[True], np.diff(t) > 1e-12])
    t, v = t[keep], v[keep]
    return CubicSpline(np.append(t, t[0] + PERIOD), np.append(v, v[0]), bc_type="periodic")


def _at(spline: CubicSpline, theta: Array) -> Array:
    t0 = float(spline.x[0])
    return np.asarray(spline(t0 + np.mod(theta - t0, PERIOD)))


def ring_surface(
    support: Any,
    members: Sequence[Any],
    fit_tol: float,
    geom_tol: float,
    probe: bool = False,
    accept: float | None = None,
) -> FittedSurface | str:
    """The fitted surface of the merged face made of ``members`` (faces of the split solid:
    a piece of the supporting plane or cylinder ``support`` and one blend half whose
    contact with it is one closed curve round the axis), to ``fit_tol`` (length unit); the
    reason (str) when the route does not apply or the fit misses ``fit_tol``. With
    ``probe`` only the first level is fitted and only data missing inside the face is
    refused (a cheap first check). ``accept``: the largest error taken when the fit cannot
    reach ``fit_tol`` (``fit_tol`` when None)."""
    ad = BRepAdaptor_Surface(support)
    kind = ad.GetType()
    if kind not in (GeomAbs_Plane, GeomAbs_Cylinder):
        return f"{NOT_A_RING}the ring route takes planes and cylinders only"
    most = 2 if kind == GeomAbs_Cylinder else 1  # a plane's support piece is the last span
    if not 2 <= len(members) <= most + 1:
        return f"{NOT_A_RING}the ring route takes one support piece and one blend half" + (
            " or two (one at each end of the cylinder)" if most == 2 else ""
        )
    kinds = [BRepAdaptor_Surface(m).GetType() for m in members]
    blends = [m for m, k in zip(members, kinds, strict=True) if k == GeomAbs_BSplineSurface]
    if kinds.count(kind) != 1 or len(blends) != len(members) - 1:
        return f"{NOT_A_RING}the ring route takes one support piece and B-spline blend halves"
    piece = members[kinds.index(kind)]
    blend = blends[0]
    contact = _loop_samples(_shared_edges(piece, blend), CURVE_SAMPLES)
    medial = _loop_samples(
        [e for e in edges_of(blend) if not _left_out(piece, blend, e)], CURVE_SAMPLES
    )
    if contact is None or medial is None:
        return f"{NOT_A_RING}the blend half's contact or medial edges are no closed loop"
    far_loops: tuple[Array, Array] | None = None
    if len(blends) == 2:
        far_contact = _loop_samples(_shared_edges(piece, blends[1]), CURVE_SAMPLES)
        far_medial = _loop_samples(
            [e for e in edges_of(blends[1]) if not _left_out(piece, blends[1], e)],
            CURVE_SAMPLES,
        )
        if far_contact is None or far_medial is None:
            return f"{NOT_A_RING}the blend half's contact or medial edges are no closed loop"
        far_loops = (far_contact, far_medial)
    if kind == GeomAbs_Plane:
        pl = ad.Plane()
        n, ex = xyz(pl.Axis().Direction()), xyz(pl.XAxis().Direction())
        c = contact.mean(axis=0)
        c = c - ((c - xyz(pl.Location())) @ n) * n
        args: tuple[str, Array, Array, Array, float] = ("plane", c, ex, n, 0.0)
    else:
        cyl = ad.Cylinder()
        ax = cyl.Position()
        args = (
            "cylinder",
            xyz(ax.Location()),
            xyz(ax.XDirection()),
            xyz(ax.Direction()),
            float(cyl.Radius()),
        )
    inside_pt = face_inside_point(piece)
    if inside_pt is None:
        return "no inside point on the support piece"
    frame = RingFrame.around(args[0], args[1], args[2], args[3], contact, 1.0, args[4])
    if isinstance(frame, str):
        return frame
    sign = 1.0 if frame.coords(inside_pt[None, :])[1][0] > 0 else -1.0
    if kind == GeomAbs_Plane and sign < 0:
        # a plane inside the contact curve (a boss top) holds the polar frame's pole
        return "the plane lies inside the contact curve (the ring's pole would be on it)"
    frame = replace(frame, sign=sign)
    th_m, sg_m, _ = frame.coords(medial)
    why = goes_round(th_m)
    if why:
        return f"the medial curve {why}"
    if np.any(sg_m >= 0):
        return "the medial curve is not on the blend side of the contact curve"
    sigma_m = _periodic_spline(th_m, sg_m)
    width = float(np.min(-sg_m))
    margin = BEYOND_MEDIAL * width
    support_pts = np.vstack([edge_points(e, 64) for e in edges_of(piece)])
    sig_support = frame.coords(support_pts)[1]
    s_lo = float(np.min(sg_m)) - margin
    s_hi = float(np.max(sig_support)) * 1.02 + geom_tol
    emb = surface_embedding(blend)
    if not isinstance(emb, NurbsSurface):
        return "a B-spline blend without a NURBS embedding"
    nurbs = replace(emb, extrapolate=True)
    uv_box = uv_bounds(blend)
    far: _FarHalf | None = None
    if far_loops is not None:
        got = _far_half(frame, blends[1], far_loops[0], far_loops[1], geom_tol)
        if isinstance(got, str):
            return got
        far = got
        s_hi = far.s_hi
        width = min(width, far.width)

    last: dict[bytes, tuple[Array, np.ndarray, np.ndarray]] = {}

    def h(th: Array, sg: Array) -> tuple[Array, np.ndarray, np.ndarray]:
        key = th.tobytes() + sg.tobytes()
        if key not in last:  # the last check grid is the volume's grid again
            last.clear()
            last[key] = points(th, sg)
        return last[key]

    def points(th: Array, sg: Array) -> tuple[Array, np.ndarray, np.ndarray]:
        t, s = th.ravel(), sg.ravel()
        sm = _at(sigma_m, t)
        inside = s >= sm
        ok = s >= sm - margin
        if far is not None:
            sf = _at(far.medial, t)
            inside &= s <= sf
            ok &= s <= sf + far.margin
        pts = frame.point(t, s, 0.0)
        over = np.flatnonzero((s < 0) & ok)
        if over.size:
            x, found = ray_points(nurbs, frame, t[over], s[over], uv_box, 1e-2 * fit_tol)
            pts[over] = x
            ok[over] = found
        if far is not None:
            beyond = np.flatnonzero((s > far.contact) & ok)
            if beyond.size:
                x, found = ray_points(
                    far.nurbs, frame, t[beyond], s[beyond], far.uv_box, 1e-2 * fit_tol
                )
                pts[beyond] = x
                ok[beyond] = found
        shape = th.shape
        return pts.reshape((*shape, 3)), ok.reshape(shape), inside.reshape(shape)

    # on a plane the points in the frame (e1, e2, n): the height along n is then held at
    # exactly zero over the support (the plane stays a plane); a cylinder's radial height
    # is no coordinate, its points are fitted as they are
    planar = frame.kind == "plane"
    rot = np.vstack([frame.e1, frame.e2, frame.axis]) if planar else np.eye(3)
    base = frame.origin if planar else np.zeros(3)

    def local(th: Array, sg: Array) -> tuple[Array, np.ndarray, np.ndarray]:
        pts, ok, inside = h(th, sg)
        return (pts - base) @ rot.T, ok, inside

    radius = float(np.mean(np.linalg.norm(np.cross(contact - frame.origin, frame.axis), axis=1)))
    fit = fit_radial_height(
        (s_lo, s_hi),
        [0.0] if far is None else [0.0, far.contact],
        local,
        fit_tol,
        FIRST_SPACING * width,
        radius,
        levels=1 if probe else LEVELS,
        s_fine=[True, False] if far is None else [True, False, True],
        zero_last=2 if planar else None,
    )
    if fit is None:
        return "the ring fit would need too many coefficients"
    if not np.isfinite(fit.error):
        return "the blend half's points are not all found on their rays (ring route)"
    limit = fit_tol if accept is None else max(accept, fit_tol)
    if fit.error > limit and not probe:
        return f"ring fit error {fit.error:.2e} above {limit:.2e}"
    fit = replace(fit, coef=base + fit.coef @ rot)  # poles in space
    surface = periodic_surface(fit)
    dv = _volume_change(fit, h, support, inside_pt, frame)
    spacing = float(np.diff(np.unique(fit.ts)).min())  # the blend side's spans
    return FittedSurface(surface, fit.error, spacing, dv)


@dataclass(frozen=True)
class _FarHalf:
    """The second blend half of a cylinder (at its other end), in the ring frame of the
    first: its contact line ``sigma = contact``, its medial curve ``sigma(theta)``
    (``medial``, a periodic spline), the data ``margin`` past it, the fit's ``s_hi``, its
    smallest ``width`` and the blend's NURBS copy with its UV box."""

    contact: float
    medial: CubicSpline
    margin: float
    s_hi: float
    width: float
    nurbs: NurbsSurface
    uv_box: tuple[float, float, float, float]


def _far_half(
    frame: RingFrame, blend: Any, contact: Array, medial: Array, geom_tol: float
) -> _FarHalf | str:
    """The second half of a cylinder's ring (see :class:`_FarHalf`), or why the route does
    not take it: its contact must be a line ``sigma = const`` of the first half's frame
    (parallel contact curves: the knot line of the fit), beyond the support."""
    th_c, sg_c, _ = frame.coords(contact)
    at = float(np.mean(sg_c))
    if not at > 0.0:
        return f"{NOT_A_RING}the second blend half is not at the far end of the support"
    th_m, sg_m, _ = frame.coords(medial)
    why = goes_round(th_m)
    if why:
        return f"the far medial curve {why}"
    if np.any(sg_m <= at):
        return "the far medial curve is not on the blend side of its contact curve"
    width = float(np.min(sg_m - at))
    # the contact edges of imported or built blends are approximations (to their edge
    # tolerance): off the knot line by a small share of the half's width, the curvature
    # jump costs the fit little, and its measured error decides
    if float(np.ptp(sg_c)) > PARALLEL_SHARE * width + geom_tol:
        return (
            f"{NOT_A_RING}the two blend halves' contact curves are not parallel "
            f"(the far one spans {float(np.ptp(sg_c)):.2e} across the ring frame)"
        )
    emb = surface_embedding(blend)
    if not isinstance(emb, NurbsSurface):
        return "a B-spline blend without a NURBS embedding"
    margin = BEYOND_MEDIAL * width
    return _FarHalf(
        at,
        _periodic_spline(th_m, sg_m),
        margin,
        float(np.max(sg_m)) + margin,
        width,
        replace(emb, extrapolate=True),
        uv_bounds(blend),
    )


def _left_out(piece: Any, blend: Any, edge: Any) -> bool:
    """Whether the blend's ``edge`` is no medial edge: degenerated, a seam of the blend, or
    shared with the support ``piece``."""
    if BRep_Tool.Degenerated_s(edge) or BRep_Tool.IsClosed_s(edge, blend):
        return True
    return any(edge.IsSame(e) for e in edges_of(piece))


def _volume_change(fit: PeriodicFit, h: Any, support: Any, inside_pt: Array, frame: Any) -> float:
    """Signed volume between the fit and the exact points over the face, positive where the
    solid grows: ``sum (P_fit - P) . (P_theta x P_sigma) dtheta dsigma`` at the centres of
    the check cells (the fit's derivatives by central differences), NaN when the outward
    side cannot be told."""
    tt = np.unique(periodic_knots(fit.n_theta)[DEGREE : fit.n_theta + DEGREE + 1])
    th, sg = span_samples(tt, CHECK_PER_SPAN), span_samples(fit.ts, CHECK_PER_SPAN)
    pts, ok, inside = h(*np.meshgrid(th, sg, indexing="ij"))
    p = fit(th, sg)
    e = 1e-6
    p_t = (fit(th + e, sg) - fit(th - e, sg)) / (2 * e)
    span = max(float(fit.ts[-1] - fit.ts[0]), 1e-300)
    es = e * span
    sg_in = np.clip(sg, fit.ts[0] + es, fit.ts[-1] - es)
    p_s = (fit(th, sg_in + es) - fit(th, sg_in - es)) / (2 * es)
    normal = np.cross(p_t, p_s)
    # the outward side: the fit's normal against the support's outward normal
    t0, s0, _ = frame.coords(inside_pt[None, :])
    q = fit.at(t0, s0)
    qt = (fit.at(t0 + e, s0) - fit.at(t0 - e, s0)) / (2 * e)
    qs = (fit.at(t0, s0 + es) - fit.at(t0, s0 - es)) / (2 * es)
    out = face_normal_at(support, q[0])
    if out is None:
        return float("nan")
    side = float(np.sign(np.cross(qt[0], qs[0]) @ out))
    wt = np.repeat(np.diff(tt) / CHECK_PER_SPAN, CHECK_PER_SPAN)
    ws = np.repeat(np.diff(np.unique(fit.ts)) / CHECK_PER_SPAN, CHECK_PER_SPAN)
    dens = np.einsum("ijk,ijk->ij", p - pts, normal)
    use = inside & ok
    return side * float(np.sum(np.where(use, dens, 0.0) * np.outer(wt, ws)))


def periodic_surface(fit: PeriodicFit) -> Any:
    """``Geom_BSplineSurface`` of a fit of points (coefficients (n_theta, ns, 3)): periodic
    cubic in ``u = theta`` (uniform knots ``k 2 pi / n_theta``), clamped in ``v``."""
    from OCP.collections import Array1_double, Array1_int, Array2_gp_Pnt
    from OCP.Geom import Geom_BSplineSurface
    from OCP.gp import gp_Pnt

    n, m = fit.coef.shape[:2]
    poles = Array2_gp_Pnt(1, n, 1, m)
    # OCCT's periodic pole i + 1 is the fit's folded coefficient i (checked against the
    # fit's own evaluation in the tests)
    for i in range(n):
        for j in range(m):
            poles.SetValue(i + 1, j + 1, gp_Pnt(*map(float, fit.coef[i, j])))
    uk, um = Array1_double(1, n + 1), Array1_int(1, n + 1)
    for k in range(n + 1):
        uk.SetValue(k + 1, float(k * PERIOD / n))
        um.SetValue(k + 1, 1)
    u, mult = np.unique(fit.ts, return_counts=True)
    vk, vm = Array1_double(1, len(u)), Array1_int(1, len(u))
    for k, (kv, mv) in enumerate(zip(u, mult, strict=True)):
        vk.SetValue(k + 1, float(kv))
        vm.SetValue(k + 1, int(mv))
    return Geom_BSplineSurface(poles, uk, vk, um, vm, DEGREE, DEGREE, True, False)
