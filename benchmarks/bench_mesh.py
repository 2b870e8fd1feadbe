"""Benchmark: medax quad meshes vs gmsh transfinite + recombine on every shared region.

For each region of ``regions.json`` and each size N x N (16, 32, 128, 512 by default), the
same run meshes the region with medax (``method="ratio"``, without the quality pass
``smooth=False``: "medax ratio", and with it, the default: "medax smooth"), with gmsh
transfinite + recombine
(the same boundary division counts, exact geometry: lines, circle arcs and the same B-splines)
and with gmsh transfinite + ``Mesh.Smoothing = 100``. It prints the quality side by side
(scaled Jacobian min / 5th percentile, min angle min / 5th percentile, inverted count, all by
medax's Verdict code on both meshes) and the time ratio to gmsh transfinite; then the
targets of issue 22: the 5th-percentile scaled Jacobian and the minimum angle of medax (with
the pass) at least gmsh TFI+smoothing's and TFI's, and the times of medax without the pass
/ gmsh TFI and with it / gmsh TFI+smoothing. Finally the
peak memory of a medax 512 x 512 mesh (largest region) is measured in a fresh subprocess
(``ru_maxrss``, and ``tracemalloc`` for the Python heap).

    python benchmarks/bench_mesh.py [--sizes 16,32,128,512] [--regions a,b] [--repeat 3]
                                    [--angle] [--paper] [--no-exact] [--no-smooth]

Each mesher runs ``--repeat`` times per region and size (medax, gmsh transfinite, medax
with the pass and gmsh transfinite + smoothing in turn) and its fastest run is reported: on
a shared machine one run's time moves by 30 % or more, the fastest of a few much less.

``--angle`` adds ``method="angle"`` (angle-weighted ratio curves on all line and arc pairs);
``--paper`` adds the paper's recursion (``method="paper"``) at the sizes up to 32.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from medax.geometry import Region, read_regions, sample_regions_path
from medax.mesh import mesh_region, quad_quality
from medax.mesh.gmsh_transfinite import gmsh_curve

ROOT = Path(__file__).resolve().parent.parent
SHARED = ROOT.parent / "shared" / "bench" / "regions.json"
T = TypeVar("T")


def regions_file() -> Path:
    return SHARED if SHARED.is_file() else sample_regions_path()


def gmsh_mesh(region: Region, n1: int, n2: int, smoothing: int) -> tuple[np.ndarray, np.ndarray,
                                                                        float, float]:  # fmt: skip
    """gmsh transfinite + recombine: (points, quads, seconds, boundary deviation)."""
    import gmsh

    t0 = time.perf_counter()
    gmsh.clear()
    gmsh.model.add(region.name)
    occ = gmsh.model.occ
    corners = [occ.addPoint(x, y, 0.0) for x, y in region.corners]
    curves = [gmsh_curve(gmsh, region.sides[k], corners[k], corners[(k + 1) % 4])
              for k in range(4)]  # fmt: skip
    loop = occ.addCurveLoop(curves)
    surf = occ.addPlaneSurface([loop])
    occ.synchronize()
    for k, c in enumerate(curves):
        gmsh.model.mesh.setTransfiniteCurve(c, (n1 if k % 2 == 0 else n2) + 1)
    gmsh.model.mesh.setTransfiniteSurface(surf, cornerTags=corners)
    gmsh.model.mesh.setRecombine(2, surf)
    gmsh.option.setNumber("Mesh.Smoothing", smoothing)
    gmsh.model.mesh.generate(2)
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    etypes, _, enodes = gmsh.model.mesh.getElements(2)
    dt = time.perf_counter() - t0
    pts = np.zeros((int(tags.max()) + 1, 2))
    pts[tags.astype(np.int64)] = xyz.reshape(-1, 3)[:, :2]
    quads = np.asarray(enodes[list(etypes).index(3)], dtype=np.int64).reshape(-1, 4)
    # geometry check: gmsh's sides against ours
    dev = 0.0
    for k, c in enumerate(curves):
        lo, hi = gmsh.model.getParametrizationBounds(1, c)
        par = np.linspace(lo[0], hi[0], 50)
        g = np.asarray(gmsh.model.getValue(1, c, par)).reshape(-1, 3)[:, :2]
        dev = max(dev, float(region.sides[k].closest(g).distance.max()))
    return pts, quads, dt, dev


def orient(pts: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """Quads made counter-clockwise when gmsh's surface normal points to -z."""
    p = pts[quads]
    area = np.sum(p[:, :, 0] * np.roll(p[:, :, 1], -1, 1) - np.roll(p[:, :, 0], -1, 1) * p[:, :, 1],
                  axis=1)  # fmt: skip
    return quads[:, ::-1] if np.median(area) < 0 else quads


def stats(pts: np.ndarray, quads: np.ndarray) -> dict[str, float]:
    s = quad_quality(pts, quads).summary()
    return {"sj_min": s["scaled_jacobian"]["min"], "sj_p5": s["scaled_jacobian"]["p5"],
            "ang_min": s["min_angle"]["min"], "ang_p5": s["min_angle"]["p5"],
            "inv": s["n_inverted"]}  # fmt: skip


def peak_rss_mib() -> float:
    """Peak resident set size of this process (MiB): ``VmHWM`` of ``/proc/self/status``
    (this program's own, reset by exec), else ``ru_maxrss`` (which on Linux a child
    inherits from the process that forked it: the parent's meshes would count)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def timed(run: Callable[..., T], *args: Any, **kw: Any) -> tuple[T, float]:
    """``run(*args, **kw)`` and its wall time (s)."""
    t0 = time.perf_counter()
    out = run(*args, **kw)
    return out, time.perf_counter() - t0


def best_of(repeat: int, run: Callable[..., T], *args: Any, **kw: Any) -> tuple[T, float]:
    """The last result of ``repeat`` calls of ``run(*args, **kw)`` and the fastest call's
    time (s)."""
    best = np.inf
    for _ in range(repeat):
        out, t = timed(run, *args, **kw)
        best = min(best, t)
    return out, best


def memory_child(name: str, n: int) -> None:
    """Run in a subprocess: one medax n x n mesh; print peak RSS and Python heap (MiB)."""
    import tracemalloc

    region = read_regions(regions_file())[name]
    base = peak_rss_mib()
    tracemalloc.start()
    t0 = time.perf_counter()
    mesh = mesh_region(region, (n, n))
    mesh.quality()
    dt = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    print(json.dumps({"rss_mib": peak_rss_mib(), "rss_before_mib": base,
                      "heap_peak_mib": peak / 2**20, "time_s": dt}))  # fmt: skip


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="16,32,128,512")
    ap.add_argument(
        "--repeat", type=int, default=3,
        help="runs of each mesher per region and size; the fastest is reported (default 3)",
    )  # fmt: skip
    ap.add_argument("--regions", default="")
    ap.add_argument("--angle", action="store_true", help="add method='angle'")
    ap.add_argument(
        "--no-exact", action="store_true", help="leave out medax with every node solved (tol=0)"
    )
    ap.add_argument("--paper", action="store_true", help="add method='paper' at N <= 32")
    ap.add_argument(
        "--no-smooth", action="store_true", help="leave out medax with the quality pass"
    )
    ap.add_argument("--memory-child", nargs=2, metavar=("REGION", "N"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.memory_child:
        memory_child(args.memory_child[0], int(args.memory_child[1]))
        return 0
    import gmsh

    regions = read_regions(regions_file())
    names = [s for s in args.regions.split(",") if s] or list(regions)
    sizes = [int(s) for s in args.sizes.split(",")]
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    head = (f"{'region':15s} {'N':>4s} {'mesher':12s} {'time s':>8s} {'sj min':>7s} {'sj p5':>7s}"
            f" {'ang min':>7s} {'ang p5':>7s} {'inv':>4s}  {'t/gmsh':>7s}")  # fmt: skip
    print(f"regions: {regions_file()}")
    print(head)
    print("-" * len(head))
    verdict = []
    for name in names:
        region = regions[name]
        for n in sizes:
            # medax and gmsh transfinite in turn, without and with smoothing, each timed by
            # its fastest of the repeats
            t_medax = t_gmsh = t_smooth = t_sm = np.inf
            for _ in range(args.repeat):
                m, t = timed(mesh_region, region, (n, n), smooth=False)
                t_medax = min(t_medax, t)
                gp, gq, t, dev = gmsh_mesh(region, n, n, 0)
                t_gmsh = min(t_gmsh, t)
                if not args.no_smooth:
                    ms, t = timed(mesh_region, region, (n, n), smooth=True)
                    t_smooth = min(t_smooth, t)
                sp, sq, t, _ = gmsh_mesh(region, n, n, 100)
                t_sm = min(t_sm, t)
            rows = [("medax ratio", m.points, m.quads, t_medax)]
            if not args.no_smooth:
                rows.append(("medax smooth", ms.points, ms.quads, t_smooth))
            if not args.no_exact:
                me, t = best_of(args.repeat, mesh_region, region, (n, n), tol=0.0, smooth=False)
                rows.append(("medax exact", me.points, me.quads, t))
            if args.angle:
                ma, t = best_of(
                    args.repeat, mesh_region, region, (n, n), method="angle", smooth=False
                )
                rows.append(("medax angle", ma.points, ma.quads, t))
            if args.paper and n <= 32:
                mp, t = best_of(
                    args.repeat, mesh_region, region, (n, n), method="paper", tol=1e-7,
                    smooth=False,
                )  # fmt: skip
                rows.append(("medax paper", mp.points, mp.quads, t))
            rows.append(("gmsh TFI", gp, orient(gp, gq), t_gmsh))
            rows.append(("gmsh TFI+sm", sp, orient(sp, sq), t_sm))
            res = {}
            for label, pts, quads, t in rows:
                s = stats(pts, quads)
                res[label] = s
                print(f"{name:15s} {n:4d} {label:12s} {t:8.3f} {s['sj_min']:7.3f} {s['sj_p5']:7.4f}"
                      f" {s['ang_min']:8.4f} {s['ang_p5']:7.2f} {s['inv']:4d}  "
                      f"{t / t_gmsh:7.2f}")  # fmt: skip
            times = {label: t for label, _, _, t in rows}
            verdict.append((name, n, res, times, dev))
    gmsh.finalize()
    print("\nissue 22 targets: sj p5 and min angle >= gmsh TFI+sm's and TFI's; time "
          "without the pass / gmsh TFI, with it / gmsh TFI+sm; gmsh sides' deviation:")  # fmt: skip
    for name, n, res, times, dev in verdict:
        words = []
        for label in ("medax ratio", "medax smooth"):
            if label not in res:
                continue
            a = res[label]
            ok = all(
                a["sj_p5"] >= res[g]["sj_p5"] - 1e-12 and a["ang_min"] >= res[g]["ang_min"] - 1e-9
                for g in ("gmsh TFI", "gmsh TFI+sm")
            )
            words.append(f"{label.split()[1]} {'met' if ok else 'MISSED'}")
        ratio = times["medax ratio"] / times["gmsh TFI"]
        sm = times.get("medax smooth", np.nan) / times["gmsh TFI+sm"]
        print(f"  {name:15s} {n:4d}  quality {', '.join(words)}  time x{ratio:.2f} / TFI, "
              f"smooth x{sm:.2f} / TFI+sm  (gmsh sides within {dev:.1e})")  # fmt: skip
    big = max(sizes)
    worst = "wavy" if "wavy" in names else names[0]
    out = subprocess.run([sys.executable, __file__, "--memory-child", worst, str(big)],
                         capture_output=True, text=True, check=True)  # fmt: skip
    mem = json.loads(out.stdout.strip().splitlines()[-1])
    print(
        f"\nmemory, medax {big}x{big} on {worst} in a fresh process: peak RSS "
        f"{mem['rss_mib']:.0f} MiB (interpreter + imports {mem['rss_before_mib']:.0f} MiB), "
        f"Python heap peak {mem['heap_peak_mib']:.0f} MiB, {mem['time_s']:.1f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
