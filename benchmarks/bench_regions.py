"""Benchmark: medax against gmsh transfinite on the random valid regions of issue 24.

The same regions as ``tests/test_untangle_regions.py`` (``tests/region_catalogue.py``: 300
valid regions, line, arc, B-spline and polyline sides, convex and non-convex, scales 1e-3
to 1e3, a fixed seed), each at 16x16 and 7x23 divisions, in one run:

- medax ``mesh_region`` (ratio method, the untangling stage where the medial grid is
  tangled or degenerate; a refusal counts as no mesh; ``smooth=False``), and the same with
  ``smooth=True`` (the quality pass, ``medax mesh``'s default);
- gmsh transfinite + recombine, and the same with ``Mesh.Smoothing = 100``.

Per mesher: the share of the meshes with no inverted quad, then over those meshes the
smallest scaled Jacobian, the 5th percentile of all their quads' scaled Jacobians pooled,
and the median of the per-mesh 5th percentiles; also on the meshes all four made without
inversion. ``--options`` then reruns medax on the cases where the untangling stage ran,
once per option alone (``knupp``, ``knupp-fixed``, ``winslow``), to compare them.

    python benchmarks/bench_regions.py [--count 300] [--options]
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

from medax.errors import MeshError
from medax.mesh import mesh_region, quad_quality
from medax.mesh import untangle as untangle_mod
from medax.mesh.gmsh_transfinite import gmsh_transfinite

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from region_catalogue import valid_regions  # noqa: E402

DIVISIONS = ((16, 16), (7, 23))
MESHERS = ("medax", "medax smooth", "gmsh TFI", "gmsh TFI+sm")


def _sj(points: np.ndarray, quads: np.ndarray) -> np.ndarray:
    return quad_quality(points, quads).scaled_jacobian


def _medax(region, n1: int, n2: int, smooth: bool = False) -> tuple[np.ndarray | None, dict]:
    try:
        m = mesh_region(region, divisions=(n1, n2), smooth=smooth)
    except MeshError as err:
        return None, {"refused": str(err)}
    return _sj(m.points, m.quads), m.info


def _table(results: dict[str, list[np.ndarray | None]], keys: list[int] | None = None) -> None:
    print(f"{'mesher':12s} {'meshes':>7s} {'no inv.':>8s} {'share':>7s} {'sj min':>8s} "
          f"{'sj p5 pooled':>12s} {'median p5':>9s}")  # fmt: skip
    for name, runs in results.items():
        sel = [runs[i] for i in (keys if keys is not None else range(len(runs)))]
        good = [s for s in sel if s is not None and s.min() > 0.0]
        if good:
            allq = np.concatenate(good)
            worst, p5 = float(min(s.min() for s in good)), float(np.percentile(allq, 5.0))
            med = float(np.median([np.percentile(s, 5.0) for s in good]))
        else:
            worst = p5 = med = float("nan")
        print(f"{name:12s} {len(sel):7d} {len(good):8d} {len(good) / max(len(sel), 1):7.1%} "
              f"{worst:8.3f} {p5:12.3f} {med:9.3f}")  # fmt: skip


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=300, help="valid regions (default 300)")
    ap.add_argument("--options", action="store_true", help="compare the untangling options")
    args = ap.parse_args()
    logging.disable(logging.WARNING)
    regions = valid_regions(args.count)
    results: dict[str, list[np.ndarray | None]] = {m: [] for m in MESHERS}
    times = dict.fromkeys(MESHERS, 0.0)
    staged: list[tuple[int, int, int]] = []  # (case, n1, n2) where the stage ran
    kept: Counter[str] = Counter()  # the option kept where the stage ran
    refusals: list[str] = []
    case = 0
    for seed, _, region in regions:
        for n1, n2 in DIVISIONS:
            t0 = time.perf_counter()
            sj, info = _medax(region, n1, n2)
            times["medax"] += time.perf_counter() - t0
            results["medax"].append(sj)
            if "refused" in info:
                refusals.append(f"  region {seed} {n1}x{n2}: {info['refused']}")
            if "untangle" in info:
                staged.append((case, n1, n2))
                kept[info["untangle"].get("option", "").split(",")[0] or "none valid"] += 1
            t0 = time.perf_counter()
            results["medax smooth"].append(_medax(region, n1, n2, smooth=True)[0])
            times["medax smooth"] += time.perf_counter() - t0
            for name, smoothing in (("gmsh TFI", 0), ("gmsh TFI+sm", 100)):
                t0 = time.perf_counter()
                pts, quads = gmsh_transfinite(region, n1, n2, smoothing)
                times[name] += time.perf_counter() - t0
                results[name].append(_sj(pts, quads))
            case += 1
    print(f"{len(regions)} valid regions x {len(DIVISIONS)} division counts = {case} meshes "
          f"per mesher (seeds {regions[0][0]} - {regions[-1][0]})")  # fmt: skip
    _table(results)
    common = [i for i in range(case) if all(
        (s := results[m][i]) is not None and s.min() > 0.0 for m in MESHERS)]  # fmt: skip
    print(f"\non the {len(common)} meshes that all four made without inversion:")
    _table(results, common)
    print("\ntime (s, all meshes): " + ", ".join(f"{m} {t:.1f}" for m, t in times.items()))
    print(f"\nmedax refusals ({len(refusals)}):")
    print("\n".join(refusals) or "  none")
    print(f"\nthe untangling stage ran on {len(staged)} meshes; option kept: {dict(kept)}")
    if args.options:
        by_case = [(r, d) for r in regions for d in DIVISIONS]
        saved = untangle_mod.OPTIONS
        rows: dict[str, list[np.ndarray | None]] = {}
        for opts in (saved, *((o,) for o in saved)):
            untangle_mod.OPTIONS = opts
            label = "+".join(opts)
            rows[label] = []
            t0 = time.perf_counter()
            for i, n1, n2 in staged:
                rows[label].append(_medax(by_case[i][0][2], n1, n2)[0])
            print(f"  {label}: {time.perf_counter() - t0:.1f} s")
        untangle_mod.OPTIONS = saved
        print(f"\nuntangling options alone, on those {len(staged)} meshes:")
        _table(rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
