"""Both equations of the ratio grid on planar regions with free-form sides, solved by a
compiled node Newton.

The general path (:func:`medax.mesh.ratio_grid._newton` with
:func:`~medax.mesh.ratio_field.evaluate_field`) handles every region: surfaces, angle
weights, feet on curves of any kind. On the common free-form case (planar, both pairs
weighted by distance, every side a segment, an arc or a curve with
:meth:`~medax.geometry.curve.Curve.jet_rows`) this module runs the same damped Newton (same
steps, cap, backtracking, acceptance and tolerance, feet tracked for small moves and
certified global after long ones, two starts where the coarse feet jump) node by node in
one compiled kernel (:func:`medax.geometry.field_kernel.free_newton`): the closed-form
sides through their terms, the tracked ones through the tracking of
:func:`~medax.geometry.curve.track_rows` on their stacked polynomial table. Between its
calls only the trial points of long steps are handled here (their tracked feet certified,
a global query where that is not shown). Its feet and distances go back to the
:class:`~medax.mesh.ratio_field.SideDistances` for the global check that follows.
"""

from __future__ import annotations

import numpy as np

from medax.geometry import field_kernel as fk
from medax.geometry import kernels
from medax.geometry._types import FloatArray
from medax.geometry.arc import Arc
from medax.geometry.bspline import BSpline
from medax.geometry.curve import Curve, certify_closest, has_closed_form_closest
from medax.geometry.line import Line
from medax.geometry.region import Region
from medax.mesh.ratio_field import SideDistances, _arc_consts, _segment_consts

_BLOCK = 16384  # nodes solved together (their state stays in cache)


def _tracked_curve(c: Curve) -> bool:
    return not has_closed_form_closest(c) and c.jet_rows(np.zeros(1)) is not None


class FreeField:
    """The sides of a region for :func:`medax.geometry.field_kernel.free_newton`: segments
    and arcs by the constants of their terms, the others (tracked) in one polynomial table
    (curve ``j`` of them on parameters ``2 j + t``)."""

    def __init__(self, sides: SideDistances, slack: float = 0.0) -> None:
        self.slack = slack  # of the certification of feet tracked over long moves
        region = sides.region
        self.curves = [region.sides[k] for k in range(4)]
        self.tracked = [_tracked_curve(c) and type(c) not in (Line, Arc) for c in self.curves]
        self.step_tol = list(getattr(sides, "step_tol", [1e-6] * 4))
        free = [c for c, tr in zip(self.curves, self.tracked, strict=True) if tr]
        table = BSpline.stacked_rows(free) if free else None  # type: ignore[arg-type]
        if table is None:  # (a tracked side is a polynomial B-spline: see :meth:`supports`)
            table = (np.zeros(0), np.zeros(1), np.zeros((1, 2, 1)))
        self.table = table
        order = np.cumsum(self.tracked) - 1
        # per side: kind, table offset, tracking step tolerance, constants of its term
        self.sides = np.zeros((4, 13))
        for k, c in enumerate(self.curves):
            if type(c) is Line:
                self.sides[k, 3:8] = _segment_consts(c)  # type: ignore[arg-type]
            elif type(c) is Arc:
                self.sides[k, 0], self.sides[k, 3:] = 1.0, _arc_consts(c)  # type: ignore[arg-type]
            else:
                self.sides[k, :3] = 2.0, 2.0 * float(order[k]), self.step_tol[k]

    @staticmethod
    def supports(region: Region, kinds: tuple[str, str]) -> bool:
        """Planar, both pairs weighted by distance, every side a segment, an arc or a curve
        with component-row jets, at least one of the last (else
        :class:`~medax.mesh.ratio_field.PlanarField` is the path)."""
        if kinds != ("distance", "distance"):
            return False
        if not region.embedding.is_identity or region.space_sides is not None:
            return False
        free = False
        for c in region.sides:
            if c.dim != 2:
                return False
            if type(c) in (Line, Arc):
                continue
            if type(c) is not BSpline or not _tracked_curve(c):
                return False
            free = True
        return free


def newton_free(
    sides: SideDistances,
    p: FloatArray,
    ra_all: FloatArray,
    rb_all: FloatArray,
    rows: np.ndarray,
    tol: float,
    iters: int,
    track_step: float,
) -> tuple[FloatArray, int, FloatArray]:
    """:func:`medax.mesh.ratio_grid._newton` on :class:`FreeField` (the same arguments and
    results; the feet start from and end in ``sides``), in blocks of ``_BLOCK`` nodes.

    A full Newton step ``s`` whose remainder is bounded below ``tol / 2`` is taken without
    evaluating the equations at its end: by Taylor's theorem each ``g`` there is at most
    ``|s|^2 / 2`` times the largest norm of its Hessian along the step, bounded by twice the
    weighted sum of the distances' Hessian bounds at its start (``(|C'' . u| / g' + 1 / d)``
    on a tracked side: the curvature of the parallel curve through the point, ``1 / d``
    where the foot is an end; ``1 / d`` on a segment, ``1 / d + 1 / rho`` on an arc, ``rho``
    the distance to its centre; only where ``|s|`` times each of those is at most 0.05, so
    that they change by a few per cent along it). The node's residual is then that bound,
    its feet stay (their points lie on the sides: the distances to them, stored for the
    global check, are upper bounds of the true ones, off by less than the bound)."""
    kernels.announce_compile()
    field = FreeField(sides, tol)
    n = rows.size
    at: np.ndarray | slice = slice(None) if n == ra_all.size else rows
    r = np.stack((ra_all[at], rb_all[at]))
    xs = np.ascontiguousarray(p, dtype=np.float64)
    tracked = [k for k in range(4) if field.tracked[k]]
    # per side the feet, in (and out), and the second starts, in (the distances, out)
    tio = np.full((8, n), np.nan)
    for k in tracked:
        tio[k], tio[4 + k] = sides.t[k][at], sides.t_alt[k][at]
    res = np.empty(n)
    par = np.array([tol, track_step * sides.region.diagonal, 0.1 * sides.region.diagonal])
    inner, starts, table = field.table
    it = 0
    for s in range(0, n, _BLOCK):
        e = min(n, s + _BLOCK)
        m = e - s
        xb, rblk, tb = xs[s:e], r[:, s:e].copy(), tio[:, s:e].copy()
        # (the kernel reads only the tracked sides' columns of these, and writes them first)
        fs, ist = np.empty((m, fk.WIDTH)), np.empty((m, 3), dtype=np.int64)
        for k in tracked:
            none = np.flatnonzero(np.isnan(tb[k]))  # no start: a global query
            if none.size:
                c = field.curves[k].closest(xb[none])
                at_k = fk.PEND + np.array([fk.T + k, fk.FOOT + 2 * k, fk.FOOT + 2 * k + 1])
                fs[none[:, None], at_k] = np.column_stack((c.t, c.foot))
        first = True
        while fk.free_newton(
            field.sides, inner, starts, table, xb, rblk, tb, fs, ist, par, iters, first
        ):
            first = False
            _certify(field, fs, ist, tracked)
        res[s:e] = fs[:, fk.RES]
        tio[:, s:e] = tb
        it = max(it, int(ist[:, 1].max(initial=0)))
    for k in tracked:
        sides.t[k][at], sides.d[k][at] = tio[k], tio[4 + k]
        sides.t_alt[k][at] = np.nan
    return xs, it, res


def _certify(field: FreeField, fs: FloatArray, ist: np.ndarray, tracked: list[int]) -> None:
    """The tracked feet of the waiting nodes' trial points (the kernel's state ``fs``)
    certified global (:func:`~medax.geometry.curve.certify_closest`, slack ``field.slack``),
    a global query where that is not shown; the nodes then resume."""
    wait = np.flatnonzero(ist[:, 0] == fk.WAIT)
    q = fs[wait, fk.STP + 4 : fk.STP + 6]
    for k in tracked:
        t_at, x_at = fk.PEND + fk.T + k, fk.PEND + fk.FOOT + 2 * k
        fx, fy = fs[wait, x_at], fs[wait, x_at + 1]
        rx, ry = q[:, 0] - fx, q[:, 1] - fy
        d = np.sqrt(rx * rx + ry * ry)
        ok = certify_closest(field.curves[k], q, fs[wait, t_at], d, field.slack)
        if not ok.all():
            bad = np.flatnonzero(~ok)
            c = field.curves[k].closest(q[bad])
            at = wait[bad]
            fs[at, t_at], fs[at, x_at], fs[at, x_at + 1] = c.t, *c.foot.T
            fs[at, fk.PEND + fk.KAP + k] = np.inf
    ist[wait, 0] = fk.RESUME
