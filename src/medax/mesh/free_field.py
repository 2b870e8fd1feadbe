"""Both equations of the ratio grid on planar regions with free-form sides, solved on
coordinate rows.

The general path (:func:`medax.mesh.ratio_grid._newton` with
:func:`~medax.mesh.ratio_field.evaluate_field`) handles every region: surfaces, angle
weights, feet on curves of any kind. On the common free-form case (planar, both pairs
weighted by distance, every side a segment, an arc or a curve with
:meth:`~medax.geometry.curve.Curve.jet_rows`) this module runs the same damped Newton (same
steps, cap, backtracking, acceptance and tolerance, feet tracked for small moves and found
by a global query for long ones, two starts where the coarse feet jump) with the points held
as two contiguous coordinate rows, the closed-form sides through the terms of
:class:`~medax.mesh.ratio_field.PlanarField` and the tracked ones through
:func:`~medax.geometry.curve.track_rows`: no ``(n, 2)`` columns, no per-evaluation
bookkeeping of foot tuples, only the rows still unconverged evaluated. Its feet and
distances go back to the :class:`~medax.mesh.ratio_field.SideDistances` for the global
check that follows.
"""

from __future__ import annotations

import numpy as np

from medax.geometry._types import FloatArray
from medax.geometry.arc import Arc
from medax.geometry.bspline import BSpline
from medax.geometry.curve import Curve, certify_closest, has_closed_form_closest, track_rows
from medax.geometry.line import Line
from medax.geometry.region import Region
from medax.mesh.ratio_field import (
    SideDistances,
    _arc_consts,
    _arc_term,
    _segment_consts,
    _segment_term,
)

_TINY = np.finfo(float).tiny
_BLOCK = 16384  # nodes solved together (the temporaries stay in cache)
_BACKTRACKS = 12
_LOCAL = 0.05  # a step unevaluated only if at most this times each distance's curvature radius


def _tracked_curve(c: Curve) -> bool:
    return not has_closed_form_closest(c) and c.jet_rows(np.zeros(1)) is not None


class FreeField:
    """The distance-weighted field of both pairs on coordinate rows: per side ``w d`` and
    ``w u`` (``u`` the unit vector from the foot) in closed form for segments and arcs,
    from tracked feet for the others."""

    def __init__(self, sides: SideDistances, slack: float = 0.0) -> None:
        self.slack = slack  # of the certification of feet tracked over long moves
        region = sides.region
        self.curves = [region.sides[k] for k in range(4)]
        self.tracked = [_tracked_curve(c) and type(c) not in (Line, Arc) for c in self.curves]
        self.consts = [
            _segment_consts(c) if type(c) is Line else _arc_consts(c) if type(c) is Arc else ()  # type: ignore[arg-type]
            for c in self.curves
        ]
        self.step_tol = list(getattr(sides, "step_tol", [1e-6] * 4))
        # the tracked sides in one table (curve j of them on parameters 2 j + t)
        free = [c for c, tr in zip(self.curves, self.tracked, strict=True) if tr]
        self.table = None
        if free and all(type(c) is BSpline for c in free):
            self.table = BSpline.stacked_rows(free)  # type: ignore[arg-type]
        order = np.cumsum(self.tracked) - 1
        self.offset = [2.0 * float(order[k]) for k in range(4)]

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
            if not _tracked_curve(c):
                return False
            free = True
        return free

    def _feet(
        self,
        xs: FloatArray,
        t0: list[FloatArray | None],
        cold: np.ndarray | None,
        t1: list[FloatArray | None] | None,
    ) -> tuple[list[FloatArray | None], list[FloatArray | None], list[FloatArray | None]]:
        """Feet (n,), foot points (2, n) and curvature terms (n,; :func:`track_rows`, inf
        where not known) on every tracked side (None on the others) of
        points ``xs`` (2, n): tracked from ``t0``, found by a global query where ``t0`` is
        NaN; on rows ``cold`` (bool, or None: none; points that moved far, past where a
        foot may jump) tracked too, then certified global
        (:func:`~medax.geometry.curve.certify_closest`, slack ``self.slack``) and queried
        globally where that is not shown; rows with a second start in ``t1`` (NaN: none)
        track it too and keep the nearer foot. The tracked sides' Newton runs once for all
        of them (one compiled call on their stacked table: :func:`track_rows`)."""
        n = xs.shape[1]
        t_out: list[FloatArray | None] = [None] * 4
        f_out: list[FloatArray | None] = [None] * 4
        # (side, rows or None for all, starts) of the tracking, in order
        runs: list[tuple[int, np.ndarray | None, FloatArray]] = []
        alts: list[tuple[int, np.ndarray, FloatArray]] = []
        colds: list[tuple[int, np.ndarray]] = []
        checks: list[tuple[int, np.ndarray]] = []
        for k in range(4):
            tk = t0[k]
            if not self.tracked[k] or tk is None:
                continue
            nan = np.isnan(tk)
            if nan.any():
                iw = np.flatnonzero(~nan)
                runs.append((k, iw, tk[iw]))
                colds.append((k, np.flatnonzero(nan)))
            else:
                runs.append((k, None, tk))
            if cold is not None:
                far = np.flatnonzero(cold & ~nan)
                if far.size:
                    checks.append((k, far))
            alt = None if t1 is None else t1[k]
            if alt is not None:
                two = np.flatnonzero(~np.isnan(alt) & ~nan)
                if two.size:
                    alts.append((k, two, alt[two]))
        every = runs + alts
        starts = np.concatenate([r[2] for r in every])
        pts = np.concatenate([xs if r[1] is None else xs[:, r[1]] for r in every], axis=1)
        sizes = [r[2].size for r in every]
        if self.table is not None:
            table = self.table
            sides = [r[0] for r in every]
            offset = np.repeat(np.array([self.offset[k] for k in sides]), sizes)
            tols = {self.step_tol[k] for k in sides}
            # (one tolerance for all: no per-row array to build and gather)
            tol: float | FloatArray = (
                tols.pop()
                if len(tols) == 1
                else np.repeat(np.array([self.step_tol[k] for k in sides]), sizes)
            )
            t_all, f_all, h_all = track_rows((table, offset), pts, starts, tol)
        else:  # (curves that do not stack: one tracking per run)
            res = [
                track_rows(self.curves[r[0]], pts[:, a : a + m], starts[a : a + m],
                           self.step_tol[r[0]])
                for r, a, m in zip(every, np.cumsum([0, *sizes[:-1]]), sizes, strict=True)
            ]  # fmt: skip
            t_all = np.concatenate([q[0] for q in res])
            f_all = np.concatenate([q[1] for q in res], axis=1)
            h_all = np.concatenate([q[2] for q in res])
        h_out: list[FloatArray | None] = [None] * 4
        a = 0
        for k, rows, tk in runs:
            m = tk.size
            if rows is None:  # (views: the runs and the alternatives do not overlap)
                t_out[k], f_out[k] = t_all[a : a + m], f_all[:, a : a + m]
                h_out[k] = h_all[a : a + m]
            else:
                tn, fn, hn = np.empty(n), np.empty((2, n)), np.full(n, np.inf)
                tn[rows], fn[:, rows] = t_all[a : a + m], f_all[:, a : a + m]
                hn[rows] = h_all[a : a + m]
                t_out[k], f_out[k], h_out[k] = tn, fn, hn
            a += m
        for k, rows in checks:  # (before the alternatives: those rows have none)
            tt, ff = t_out[k], f_out[k]
            assert tt is not None and ff is not None
            p = xs[:, rows]
            r = p - ff[:, rows]
            d = np.sqrt(r[0] * r[0] + r[1] * r[1])
            ok = certify_closest(self.curves[k], p.T, tt[rows], d, self.slack)
            if not ok.all():
                colds.append((k, rows[~ok]))
        for k, rows in colds:
            c = self.curves[k].closest(xs[:, rows].T)
            tt, ff, hh = t_out[k], f_out[k], h_out[k]
            assert tt is not None and ff is not None and hh is not None
            tt[rows], ff[:, rows], hh[rows] = c.t, c.foot.T, np.inf
        for k, rows, tk in alts:
            m = tk.size
            ta, fa = t_all[a : a + m], f_all[:, a : a + m]
            a += m
            tt, ff = t_out[k], f_out[k]
            assert tt is not None and ff is not None
            p = xs[:, rows]
            ra, rb = p - fa, p - ff[:, rows]
            better = np.flatnonzero(ra[0] * ra[0] + ra[1] * ra[1] < rb[0] * rb[0] + rb[1] * rb[1])
            sel = rows[better]
            tt[sel], ff[:, sel] = ta[better], fa[:, better]
            hh = h_out[k]
            assert hh is not None
            hh[sel] = h_all[a - m : a][better]
        return t_out, f_out, h_out

    def evaluate(
        self,
        xs: FloatArray,
        w: list[FloatArray],
        t0: list[FloatArray | None],
        cold: np.ndarray | None = None,
        t1: list[FloatArray | None] | None = None,
    ) -> tuple[
        list[FloatArray], list[FloatArray | None], list[FloatArray | None],
        list[FloatArray | None], list[FloatArray],
    ]:  # fmt: skip
        """Both equations at ``xs`` (2, n) with side weights ``w`` (per side (n,): ``1 - r``
        on sides 0 and 1, ``r`` on 2 and 3): ``[g_a, gax, gay, g_b, gbx, gby]``; the feet,
        distances and foot points (2, n) per side (None on closed-form sides), feet as
        :meth:`_feet`; and per side a bound (n,) of the norm of the distance's Hessian at
        the points: ``(|C'' . u| / g' + 1 / d)`` on a tracked side (the curvature of the
        parallel curve through the point, ``1 / d`` where the foot is an end), ``1 / d`` on a
        segment, ``1 / d + 1 / rho`` on an arc (``rho`` the distance to its centre)."""
        x, y = xs[0], xs[1]
        feet: list[FloatArray | None] = [None] * 4
        foot: list[FloatArray | None] = [None] * 4
        curv: list[FloatArray | None] = [None] * 4
        if any(self.tracked):
            feet, foot, curv = self._feet(xs, t0, cold, t1)
        parts: list[tuple[FloatArray, FloatArray, FloatArray]] = []
        dist: list[FloatArray | None] = [None] * 4
        hess: list[FloatArray] = []
        for k in range(4):
            fk, ck = foot[k], curv[k]
            if fk is None or ck is None:
                if type(self.curves[k]) is Line:
                    part = _segment_term(self.consts[k], x, y, w[k], True)
                    hess.append(w[k] / np.maximum(part[0], _TINY))
                else:
                    part = _arc_term(self.consts[k], x, y, w[k], True)
                    cx, cy = self.consts[k][0], self.consts[k][1]
                    rho = np.hypot(x - cx, y - cy)
                    hess.append(w[k] / np.maximum(part[0], _TINY) + 1.0 / np.maximum(rho, _TINY))
                parts.append(part)
                continue
            rx, ry = x - fk[0], y - fk[1]
            d = rx * rx
            d += ry * ry
            np.sqrt(d, out=d)
            inv = 1.0 / np.maximum(d, _TINY)
            hess.append((ck + 1.0) * inv)
            f = w[k] * inv
            rx *= f
            ry *= f
            parts.append((w[k] * d, rx, ry))
            dist[k] = d
        g: list[FloatArray] = []
        for a, b in ((0, 2), (1, 3)):
            pa, pb = parts[a], parts[b]
            for v, u in ((pa[0], pb[0]), (pa[1], pb[1]), (pa[2], pb[2])):
                v -= u
                g.append(v)
        return g, feet, dist, foot, hess


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
    results; the feet start from and end in ``sides``), in blocks of ``_BLOCK`` nodes."""
    field = FreeField(sides, tol)
    n = rows.size
    # every row (``rows`` are sorted and distinct): views and copies, no gathers or scatters
    at: np.ndarray | slice = slice(None) if n == ra_all.size else rows
    ra, rb = ra_all[at], rb_all[at]
    w = [1.0 - ra, 1.0 - rb, ra, rb]
    xs = np.ascontiguousarray(p.T, dtype=np.float64)
    t0 = [sides.t[k][at] if field.tracked[k] else None for k in range(4)]
    t1 = [sides.t_alt[k][at] if field.tracked[k] else None for k in range(4)]
    res = np.empty(n)
    # (on every row the blocks' feet go to ``sides`` at once: a block reads only its own)
    full = isinstance(at, slice)
    t_out = [None if f is None else f if full else np.empty(n) for f in t0]
    d_out = [None if f is None else sides.d[k] if full else np.empty(n) for k, f in enumerate(t0)]
    diag = sides.region.diagonal
    it = 0
    for s in range(0, n, _BLOCK):
        e = min(n, s + _BLOCK)
        sl = slice(s, e)
        out = (
            xs[:, sl],
            res[sl],
            [None if f is None else f[sl] for f in t_out],
            [None if f is None else f[sl] for f in d_out],
        )
        bit = _newton_block(
            field,
            xs[:, sl],
            [v[sl] for v in w],
            [None if f is None else f[sl] for f in t0],
            [None if f is None else f[sl] for f in t1],
            out,
            tol,
            diag,
            iters,
            track_step,
        )
        it = max(it, bit)
    for k in range(4):
        to, do = t_out[k], d_out[k]
        if to is not None and do is not None:
            if not full:
                sides.t[k][rows], sides.d[k][rows] = to, do
            sides.t_alt[k][at] = np.nan
    return np.ascontiguousarray(xs.T), it, res


def _newton_block(
    field: FreeField,
    xs0: FloatArray,
    w: list[FloatArray],
    t0: list[FloatArray | None],
    t1: list[FloatArray | None],
    out: tuple[FloatArray, FloatArray, list[FloatArray | None], list[FloatArray | None]],
    tol: float,
    diag: float,
    iters: int,
    track_step: float,
) -> int:
    """One block of :func:`newton_free`: fills ``out`` (nodes (2, n), which may be ``xs0``
    itself, read only before; residuals (n,); feet and distances (n,) per side, None on
    closed-form sides) and returns the iterations. Converged rows leave the working arrays
    once they are half of them.

    A full Newton step ``s`` whose remainder is bounded below ``tol / 2`` is taken without
    evaluating the equations at its end: by Taylor's theorem each ``g`` there is at most
    ``|s|^2 / 2`` times the largest norm of its Hessian along the step, bounded by twice the
    weighted sum of the distances' Hessian bounds at its start (:meth:`FreeField.evaluate`;
    only where ``|s|`` times each of those is at most ``_LOCAL``, so that they change by a
    few per cent along it). The row's residual is then that bound, its feet stay (their
    points lie on the sides: the distances to them, stored for the global check, are upper
    bounds of the true ones, off by less than the bound)."""
    n = xs0.shape[1]
    out_x, out_res, out_t, out_d = out  # (every row is stored once: at a compaction or last)
    g, t, d, f, h = field.evaluate(xs0, w, t0, None, t1)
    xs = xs0.copy()
    res = np.sqrt(g[0] * g[0] + g[3] * g[3])
    rows = np.arange(n)  # block rows held in the working arrays
    max_step = 0.1 * diag
    it = 0

    def store(sel: np.ndarray | slice, at: np.ndarray | slice) -> None:
        out_x[:, at], out_res[at] = xs[:, sel], res[sel]
        for k in range(4):
            to, tk, do, dk = out_t[k], t[k], out_d[k], d[k]
            if to is not None and tk is not None and do is not None and dk is not None:
                to[at], do[at] = tk[sel], dk[sel]

    while True:
        hot = res > tol
        count = int(np.count_nonzero(hot))
        if count == 0 or it == iters:
            break
        if 2 * count <= rows.size:  # compact: keep the unconverged rows only
            if rows.size == n:  # every row, contiguous (the kept ones are stored again)
                store(slice(None), slice(None))
            else:
                done = np.flatnonzero(~hot)
                store(done, rows[done])
            keep = np.flatnonzero(hot)
            rows, xs, res = rows[keep], xs[:, keep], res[keep]
            g = [v[keep] for v in g]
            w = [v[keep] for v in w]
            h = [v[keep] for v in h]
            t = [None if v is None else v[keep] for v in t]
            d = [None if v is None else v[keep] for v in d]
            f = [None if v is None else v[:, keep] for v in f]
            hot = np.ones(rows.size, dtype=bool)
        it += 1
        ga, gax, gay, gb, gbx, gby = g
        det = gax * gby - gay * gbx
        safe = np.where(np.abs(det) > 1e-300, det, 1e-300)
        sx = (gay * gb - gby * ga) / safe
        sy = (gbx * ga - gax * gb) / safe
        norm = np.sqrt(sx * sx + sy * sy)
        cap = np.minimum(1.0, max_step / np.maximum(norm, 1e-300))
        sx *= cap
        sy *= cap
        # full steps with a small enough remainder: taken unevaluated
        top = np.maximum(np.maximum(h[0], h[1]), np.maximum(h[2], h[3]))
        half = 0.5 * norm * norm
        # a side whose Hessian bound is unknown (inf: its foot was found by a global query)
        # gives inf, or NaN times a zero weight or step: either way the row is not "sure"
        with np.errstate(invalid="ignore", over="ignore"):
            bound = 2.0 * np.hypot(
                half * (w[0] * h[0] + w[2] * h[2]), half * (w[1] * h[1] + w[3] * h[3])
            )
            sure = hot & (cap == 1.0) & (norm * top <= _LOCAL) & (bound <= 0.5 * tol)
        if sure.any():
            _jump(xs, sx, sy, res, bound, d, f, sure)
            hot &= ~sure
        todo = np.flatnonzero(hot)
        lam = 1.0
        for _ in range(_BACKTRACKS if todo.size else 0):  # backtracking on the residual
            whole = todo.size == rows.size
            q = np.empty((2, todo.size))
            if whole:
                np.multiply(sx, lam, out=q[0])
                np.multiply(sy, lam, out=q[1])
                q += xs
            else:
                q[0] = xs[0, todo] + lam * sx[todo]
                q[1] = xs[1, todo] + lam * sy[todo]
            # feet are tracked for small moves only: a long step may cross the place where a
            # foot jumps to another part of its side, which only a global query sees
            long = lam * (norm if whole else norm[todo]) > track_step * diag
            wt = w if whole else [v[todo] for v in w]
            tt = t if whole else [None if v is None else v[todo] for v in t]
            ng, nt, nd, nf, nh = field.evaluate(q, wt, tt, long if long.any() else None)
            nres = np.sqrt(ng[0] * ng[0] + ng[3] * ng[3])
            ok = nres < (res if whole else res[todo]) * (1.0 - 1e-4 * lam) + tol
            if whole and ok.all():
                xs, res, g, t, d, f, h = q, nres, ng, nt, nd, nf, nh
                todo = todo[:0]
                break
            acc = todo[ok]
            xs[:, acc], res[acc] = q[:, ok], nres[ok]
            for v, nv in zip(g, ng, strict=True):
                v[acc] = nv[ok]
            for v, nv in zip(h, nh, strict=True):
                v[acc] = nv[ok]
            for k in range(4):
                tk, ntk, dk, ndk, fk, nfk = t[k], nt[k], d[k], nd[k], f[k], nf[k]
                if tk is not None and ntk is not None and dk is not None and ndk is not None:
                    tk[acc], dk[acc] = ntk[ok], ndk[ok]
                if fk is not None and nfk is not None:
                    fk[:, acc] = nfk[:, ok]
            todo = todo[~ok]
            if todo.size == 0:
                break
            lam *= 0.5
    store(slice(None), slice(None) if rows.size == n else rows)
    return it


def _jump(
    xs: FloatArray,
    sx: FloatArray,
    sy: FloatArray,
    res: FloatArray,
    bound: FloatArray,
    d: list[FloatArray | None],
    f: list[FloatArray | None],
    sure: np.ndarray,
) -> None:
    """The unevaluated steps of :func:`_newton_block` on rows ``sure`` (bool (m,)), in place:
    nodes ``xs`` (2, m) moved by ``(sx, sy)``, residuals ``res`` set to ``bound``, distances
    to the kept foot points ``f`` (2, m) per side. Where most rows jump (the first
    iterations) on whole rows, copied where ``sure``: 2x faster than gathers and scatters of
    them (and 4x than masked arithmetic)."""
    x, y = xs
    m = x.size
    jump = np.flatnonzero(sure)
    if 3 * jump.size <= 2 * m:
        x[jump] += sx[jump]
        y[jump] += sy[jump]
        res[jump] = bound[jump]
        for dk, fk in zip(d, f, strict=True):
            if dk is not None and fk is not None:
                rx, ry = x[jump] - fk[0, jump], y[jump] - fk[1, jump]
                dk[jump] = np.sqrt(rx * rx + ry * ry)
        return
    rx, ry = np.add(x, sx), np.empty(m)
    np.copyto(x, rx, where=sure)
    np.add(y, sy, out=rx)
    np.copyto(y, rx, where=sure)
    np.copyto(res, bound, where=sure)
    for dk, fk in zip(d, f, strict=True):
        if dk is not None and fk is not None:
            np.subtract(x, fk[0], out=rx)
            np.subtract(y, fk[1], out=ry)
            rx *= rx
            ry *= ry
            rx += ry
            np.sqrt(rx, out=rx)
            np.copyto(dk, rx, where=sure)
