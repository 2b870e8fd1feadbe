"""The volume change between two solids by rays, independent of OCCT's mass properties.

Lines along z through the centres of an n x n grid over the first solid's bounding box are
cut with each solid (``IntCurvesFace_ShapeIntersector``); the length inside is summed times
the cell area. Where the two solids share their faces the rays give the same lengths, so the
grid's own error (large: the boundary is resolved to a cell) cancels in the difference,
which converges as the changed faces are resolved. Rays with an odd number of hits
(tangent, or through an edge) are left out of both sums.

    .venv/bin/python benchmarks/ray_volume.py INPUT WRITTEN [--n 250]

INPUT is read as ``medax simplify`` reads it (classified, first solid), WRITTEN with the
reader and no face unification; prints both sums, their difference and its share.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np


def lengths(shape: Any, xs: np.ndarray, ys: np.ndarray, z0: float) -> np.ndarray:
    """Length inside ``shape`` of the line along z through each ``(x, y)``, (nx, ny); NaN
    where the line has an odd number of hits."""
    from OCP.gp import gp_Dir, gp_Lin, gp_Pnt
    from OCP.IntCurvesFace import IntCurvesFace_ShapeIntersector

    cut = IntCurvesFace_ShapeIntersector()
    cut.Load(shape, 1e-9)
    out = np.zeros((len(xs), len(ys)))
    for i, x in enumerate(xs):  # OCCT's intersector takes one line per call
        for j, y in enumerate(ys):
            cut.Perform(gp_Lin(gp_Pnt(x, y, z0), gp_Dir(0, 0, 1)), -1e300, 1e300)
            w = np.sort([cut.WParameter(k) for k in range(1, cut.NbPnt() + 1)])
            w = w[np.concatenate([[True], np.diff(w) > 1e-9])] if w.size else w  # shared edges
            out[i, j] = np.nan if w.size % 2 else float(np.sum(w[1::2] - w[0::2]))
    return out


def main() -> None:
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    from medax.cad.classify import classify_file
    from medax.cad.reader import read_part

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("input", help="the part as given to medax simplify")
    ap.add_argument("written", help="the simplified solid as written")
    ap.add_argument("--n", type=int, default=250, help="rays per direction (250)")
    args = ap.parse_args()
    a = classify_file(args.input)[0].shape
    b = read_part(args.written, unify=False).solids[0]
    box = Bnd_Box()
    BRepBndLib.Add_s(a, box)
    lo, hi = box.CornerMin(), box.CornerMax()
    hx, hy = (hi.X() - lo.X()) / args.n, (hi.Y() - lo.Y()) / args.n
    xs = lo.X() + hx * (np.arange(args.n) + 0.5)
    ys = lo.Y() + hy * (np.arange(args.n) + 0.5)
    t = time.process_time()
    la, lb = lengths(a, xs, ys, lo.Z() - 1.0), lengths(b, xs, ys, lo.Z() - 1.0)
    ok = np.isfinite(la) & np.isfinite(lb)
    va, vb = float(la[ok].sum() * hx * hy), float(lb[ok].sum() * hx * hy)
    print(
        f"rays {args.n} x {args.n} ({int((~ok).sum())} left out): input {va:.6f}, "
        f"written {vb:.6f}, change {vb - va:+.6e} ({(vb - va) / va:+.3e}), "
        f"{time.process_time() - t:.0f} s CPU"
    )


if __name__ == "__main__":
    main()
