"""Crossings of two families of curves: every curve of one family with every curve of the other.

Each curve is sampled into a dense polyline; candidate segment pairs come from a k-d tree of
segment midpoints, proper crossings from a vectorised orientation test, and each crossing is
refined on the curves themselves by Newton's method on ``A(s) - B(u) = 0``. A pair of curves
that crosses zero times or more than once is an error: the families then do not form a grid.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from medax.errors import MeshError
from medax.geometry._types import FloatArray
from medax.geometry.curve import Curve

_SAMPLES = 129  # polyline points per curve (times the curve's complexity, capped)


def _polylines(curves: Sequence[Curve]) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Sampled points, their parameters and the owning curve of every sample."""
    pts, ts, own = [], [], []
    for c, curve in enumerate(curves):
        n = int(min(_SAMPLES * max(1, curve.complexity() // 8), 4097))
        t = np.linspace(0.0, 1.0, n)
        pts.append(curve.evaluate(t))
        ts.append(t)
        own.append(np.full(n, c))
    return np.concatenate(pts), np.concatenate(ts), np.concatenate(own)


def family_crossings(
    fam_a: Sequence[Curve], fam_b: Sequence[Curve], tol: float, what: str = "curves"
) -> FloatArray:
    """Crossing points ``(len(fam_a), len(fam_b), 2)``: entry ``[j, i]`` is ``A_j`` x ``B_i``.

    ``tol`` (absolute length) is the accuracy required of the refined crossings; two
    candidate crossings of one pair further apart than ``1e3 * tol`` count as two crossings.
    """
    na, nb = len(fam_a), len(fam_b)
    out = np.full((na, nb, 2), np.nan)
    if na == 0 or nb == 0:
        return out
    pa, ta, oa = _polylines(fam_a)
    pb, tb, ob = _polylines(fam_b)
    # segments: consecutive samples of the same curve
    sa = np.nonzero(oa[:-1] == oa[1:])[0]
    sb = np.nonzero(ob[:-1] == ob[1:])[0]
    a0, a1, b0, b1 = pa[sa], pa[sa + 1], pb[sb], pb[sb + 1]
    ha = 0.5 * np.linalg.norm(a1 - a0, axis=1)
    hb = 0.5 * np.linalg.norm(b1 - b0, axis=1)
    tree_b = cKDTree(0.5 * (b0 + b1))
    radius = ha + hb.max() * (1.0 + 1e-9) + 1e-300
    cand = tree_b.query_ball_point(0.5 * (a0 + a1), r=radius)
    counts = np.fromiter((len(c) for c in cand), dtype=np.int64, count=len(cand))
    ia = np.repeat(np.arange(len(sa)), counts)
    ib = np.fromiter((j for c in cand for j in c), dtype=np.int64, count=int(counts.sum()))
    # segment intersection: a0 + s (a1 - a0) = b0 + u (b1 - b0), s, u in [0, 1]
    da, db = a1[ia] - a0[ia], b1[ib] - b0[ib]
    w = b0[ib] - a0[ia]
    den = da[:, 0] * db[:, 1] - da[:, 1] * db[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (w[:, 0] * db[:, 1] - w[:, 1] * db[:, 0]) / den
        u = (w[:, 0] * da[:, 1] - w[:, 1] * da[:, 0]) / den
    hit = (den != 0.0) & (s >= 0.0) & (s <= 1.0) & (u >= 0.0) & (u <= 1.0)
    ia, ib, s, u = ia[hit], ib[hit], s[hit], u[hit]
    ja, jb = oa[sa[ia]], ob[sb[ib]]
    sa_t = ta[sa[ia]] + s * (ta[sa[ia] + 1] - ta[sa[ia]])
    ub_t = tb[sb[ib]] + u * (tb[sb[ib] + 1] - tb[sb[ib]])
    s_ref, u_ref, err = _refine(fam_a, fam_b, ja, jb, sa_t, ub_t)
    pts = np.empty((len(ja), 2))
    for j in np.unique(ja):
        m = ja == j
        pts[m] = fam_a[j].evaluate(s_ref[m])
    # one crossing per pair: hits at a shared sample repeat the same point
    key = ja * nb + jb
    order = np.lexsort((s_ref, key))
    key, pts, err = key[order], pts[order], err[order]
    first = np.ones(len(key), dtype=bool)
    first[1:] = key[1:] != key[:-1]
    far = np.zeros(len(key), dtype=bool)
    far[1:] = (~first[1:]) & (np.linalg.norm(pts[1:] - pts[:-1], axis=1) > 1e3 * tol)
    if np.any(far):
        k = int(key[np.argmax(far)])
        raise MeshError(f"{what}: curve {k // nb} of the first family crosses curve {k % nb} "
                        "of the second more than once")  # fmt: skip
    found = np.zeros(na * nb, dtype=bool)
    found[key[first]] = True
    if not found.all():
        k = int(np.argmin(found))
        raise MeshError(f"{what}: curve {k // nb} of the first family does not cross curve "
                        f"{k % nb} of the second")  # fmt: skip
    if np.any(err[first] > tol):
        raise MeshError(f"{what}: a crossing did not converge ({err[first].max():.2e})")
    out.reshape(-1, 2)[key[first]] = pts[first]
    return out


def _refine(
    fam_a: Sequence[Curve],
    fam_b: Sequence[Curve],
    ja: np.ndarray,
    jb: np.ndarray,
    s: FloatArray,
    u: FloatArray,
    iters: int = 12,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Newton on ``A_ja(s) - B_jb(u) = 0`` from the polyline crossings; returns s, u, |gap|."""
    s, u = s.copy(), u.copy()
    groups_a = [(j, np.nonzero(ja == j)[0]) for j in np.unique(ja)]
    groups_b = [(j, np.nonzero(jb == j)[0]) for j in np.unique(jb)]

    def evaluate(fam: Sequence[Curve], groups: list, t: FloatArray) -> tuple[FloatArray, ...]:
        p, d = np.empty((t.size, 2)), np.empty((t.size, 2))
        for j, idx in groups:
            p[idx] = fam[j].evaluate(t[idx])
            d[idx] = fam[j].derivative(t[idx])
        return p, d

    for _ in range(iters):
        pa, da = evaluate(fam_a, groups_a, s)
        pb, db = evaluate(fam_b, groups_b, u)
        f = pa - pb
        # [da, -db] [ds, du]^T = -f
        det = -da[:, 0] * db[:, 1] + da[:, 1] * db[:, 0]
        det = np.where(np.abs(det) > 1e-300, det, 1e-300)
        ds = (-f[:, 0] * -db[:, 1] + db[:, 0] * -f[:, 1]) / det
        du = (da[:, 0] * -f[:, 1] - da[:, 1] * -f[:, 0]) / det
        s = np.clip(s + ds, 0.0, 1.0)
        u = np.clip(u + du, 0.0, 1.0)
        if np.all(np.abs(ds) + np.abs(du) < 1e-15):
            break
    pa, _ = evaluate(fam_a, groups_a, s)
    pb, _ = evaluate(fam_b, groups_b, u)
    return s, u, np.linalg.norm(pa - pb, axis=1)
