"""Moving points onto the axis (paper step 4), all points of a batch at once."""

from __future__ import annotations

import numpy as np

from medax.axis.field import DistanceField, FieldSample
from medax.geometry._types import FloatArray


def correct_newton(
    field: DistanceField,
    p: FloatArray,
    tol: float,
    max_iter: int = 40,
    target: float = 1e-3,
    sample: FieldSample | None = None,
) -> tuple[FloatArray, FieldSample, np.ndarray, int]:
    """Safeguarded Newton along the field gradient for points ``p`` (n, 2).

    Each step is ``-g grad / |grad|^2`` in the parameter plane, halved while it does not
    reduce ``|g|``. Iterates per point until the equidistance error ``2|g|`` is below
    ``target * tol`` (Newton is quadratic: the margin costs about one step) or stalls at
    round-off; a point has converged when ``2|g| <= tol`` (absolute).
    ``sample`` is the field at ``p`` where the caller has it (not evaluated again).
    Returns the points, the field at them, a converged mask (n,) and the iteration count.
    """
    p = np.array(p, dtype=np.float64, copy=True)
    s = field(p) if sample is None else sample
    data = s.data.copy()  # the accepted points' field, row by row
    cur = FieldSample(data, s.dim)
    g, grad = cur.g, cur.grad  # (views of data: they follow its updates)
    lam = np.ones(len(p))
    goal = target * tol
    done = 2.0 * np.abs(g) <= goal
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007
        act = np.nonzero(~done)[0]
        if act.size == 0:
            break
        ga = grad[act]
        gg = np.einsum("ij,ij->i", ga, ga)
        step = (g[act] / np.maximum(gg, 1e-300))[:, None] * ga
        trial = p[act] - lam[act, None] * step
        st = field(trial)
        better = np.abs(st.g) < np.abs(g[act])
        if act.size == p.shape[0] and better.all():  # all accepted: take the new sample
            p = trial
            data = st.data
            cur = st
            g, grad = cur.g, cur.grad
            lam[:] = 1.0
            done = 2.0 * np.abs(g) <= goal
            continue
        idx = act[better]
        p[idx] = trial[better]
        data[idx] = st.data[better]  # the accepted points' field (g and grad among them)
        lam[idx] = 1.0
        lam[act[~better]] *= 0.5
        done[idx] = 2.0 * np.abs(g[idx]) <= goal
        stuck = act[~better][lam[act[~better]] < 1e-12]
        done[stuck] = True  # no further progress possible (round-off floor)
    return p, cur, 2.0 * np.abs(cur.g) <= tol, it


def correct_paper(
    field: DistanceField, p: FloatArray, eps: float = 0.01, max_iter: int = 200
) -> tuple[FloatArray, FieldSample, int]:
    """The paper's rule: move along ``q1 q2`` by ``|d1 - d2| / 2n`` (``n`` = 1 + number of
    direction reversals) toward the farther constraint, until ``1 - eps < d1/d2 < 1 + eps``.

    Works on the axis (ratio 1/2) only; all points of ``p`` (n, 2) at once.
    """
    p = np.array(p, dtype=np.float64, copy=True)
    n_rev = np.ones(len(p))
    last_dir = np.zeros(len(p))
    s = field(p)
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007
        ratio = s.d1 / np.maximum(s.d2, 1e-300)
        act = np.nonzero(~((ratio > 1.0 - eps) & (ratio < 1.0 + eps)))[0]
        if act.size == 0:
            break
        d1, d2 = s.d1[act], s.d2[act]
        direction = np.where(d1 > d2, 1.0, -1.0)  # +1: toward A1 (from q2 to q1)
        flipped = (last_dir[act] != 0.0) & (direction != last_dir[act])
        n_rev[act] += flipped
        last_dir[act] = direction
        e = s.q1[act] - s.q2[act]
        e /= np.maximum(np.linalg.norm(e, axis=1), 1e-300)[:, None]
        move = (np.abs(d1 - d2) / (2.0 * n_rev[act]) * direction)[:, None] * e
        p[act] += _to_parameter(field, p[act], move)
        s = field(p)
    return p, s, it


def _to_parameter(field: DistanceField, p: FloatArray, v: FloatArray) -> FloatArray:
    """Space vectors ``v`` (n, dim) at ``p`` as parameter-plane vectors (least squares)."""
    emb = field.region.embedding
    if emb.is_identity:
        return v
    jac = emb.jacobian(p)
    return np.einsum("nij,nj->ni", np.linalg.pinv(jac), v)
