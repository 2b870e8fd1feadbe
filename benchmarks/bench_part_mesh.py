"""Quad meshes of whole parts: medax (medial grids on 4-sided faces, gmsh's quads on the
others) against gmsh's best all-quad surface mesh at the same size, in one run.

gmsh alone: the part imported by gmsh's OCC kernel, ``setTransfiniteAutomatic`` (transfinite
where a face allows it) then quasi-structured quads (``Mesh.Algorithm = 11``) elsewhere,
recombined; size ``--size`` (default the diagonal / ``--per``, 40). medax: ``mesh_part`` at the same
size, on the part as read and on the part after fillet simplification (its time without the
simplification's, printed apart). gmsh runs in a child process (its quasi-structured
meshing was seen to hang; it is stopped after ``--timeout`` seconds).

Per part and mesher: elements, the share of quads, the 5th percentile and minimum of
Verdict's scaled Jacobian (on the quads), the smallest angle (degrees), the time (wall,
seconds), the CPU time (gmsh's process; medax's and its gmsh workers') and, for medax,
faces structured / all; after simplify, the whole run's time (simplify + mesh) over
gmsh's, wall and CPU.

    .venv/bin/python benchmarks/bench_part_mesh.py [PART.step ...] [--size H | --per N]
        [--no-simplify]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

SHARED = Path(__file__).resolve().parents[1] / ".." / "shared" / "bench" / "cad"
STEP = ("ski_part_with_hole.step", "bm2_ec_lever-A.stp", "ANC101.stp")

_GMSH = r"""
import json, sys, time
import numpy as np
import gmsh
from medax.mesh.quality import quad_quality
path, size, out = sys.argv[1], float(sys.argv[2]), sys.argv[3]
gmsh.initialize(readConfigFiles=False, interruptible=False)
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.occ.importShapes(path)
gmsh.model.occ.synchronize()
t0, c0 = time.perf_counter(), time.process_time()
gmsh.model.mesh.setTransfiniteAutomatic()
gmsh.option.setNumber("Mesh.Algorithm", 11)
gmsh.option.setNumber("Mesh.RecombineAll", 1)
gmsh.option.setNumber("Mesh.MeshSizeMax", size)
gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
gmsh.model.mesh.generate(2)
dt, cpu = time.perf_counter() - t0, time.process_time() - c0
tags, coord, _ = gmsh.model.mesh.getNodes()
pts = np.asarray(coord).reshape(-1, 3)
index = np.full(int(max(tags)) + 1, -1)
index[np.asarray(tags, dtype=int)] = np.arange(len(tags))
types, _, conn = gmsh.model.mesh.getElements(2)
quads, others = [], 0
for t, c in zip(types, conn):
    if int(t) == 3:
        quads.append(index[np.asarray(c, dtype=int)].reshape(-1, 4))
    else:
        others += len(c) // gmsh.model.mesh.getElementProperties(int(t))[3]
q = np.concatenate(quads) if quads else np.zeros((0, 4), dtype=int)
res = {"n": len(q) + others, "quads": len(q), "time": dt, "cpu": cpu}
if len(q):
    qq = quad_quality(pts, q)
    res.update(p5=float(np.percentile(qq.scaled_jacobian, 5)),
               min=float(qq.scaled_jacobian.min()), angle=float(qq.min_angle.min()))
json.dump(res, open(out, "w"))
gmsh.finalize()
"""


def _gmsh(path: Path, size: float, timeout: float) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "r.json"
        t0 = time.perf_counter()
        try:
            subprocess.run(
                [sys.executable, "-c", _GMSH, str(path), str(size), str(out)],
                timeout=timeout,
                check=True,
                capture_output=True,
            )
        except subprocess.TimeoutExpired:
            return {"error": f"timeout {timeout:g} s"}
        except subprocess.CalledProcessError as err:
            return {"error": err.stderr.decode().strip().splitlines()[-1][:60]}
        res = json.loads(out.read_text())
        res["wall"] = time.perf_counter() - t0
        return res


def _medax(shape: Any, size: float) -> dict[str, Any]:
    from medax.cad.part_mesh import mesh_part
    from medax.errors import MedaxError
    from medax.mesh.quality import quad_quality

    t0, c0 = time.perf_counter(), _cpu()
    try:
        m = mesh_part(shape, size)
    except MedaxError as err:
        return {"error": str(err)[:60]}
    dt, cpu = time.perf_counter() - t0, _cpu() - c0
    q = quad_quality(m.points, m.quads)
    return {
        "n": len(m.quads),
        "quads": len(m.quads),
        "time": dt,
        "cpu": cpu,
        "p5": float(np.percentile(q.scaled_jacobian, 5)),
        "min": float(q.scaled_jacobian.min()),
        "angle": float(q.min_angle.min()),
        "faces": f"{len(m.structured_faces)}/{len(m.faces)}",
    }


def _cpu() -> float:
    """CPU seconds of this process and of its children that ended (gmsh's workers)."""
    import resource

    a, b = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime


def _simplified(shape: Any) -> tuple[Any, float, float, str]:
    from medax.cad.classify import classify_solid
    from medax.cad.simplify import simplify, specs_from_classification

    t0, c0 = time.perf_counter(), _cpu()
    cls = classify_solid(shape)
    r = simplify(cls.shape, specs_from_classification(cls))
    dt, cpu = time.perf_counter() - t0, _cpu() - c0
    return r.shape, dt, cpu, f"{r.faces_before}->{r.faces_after}"


def _parts(paths: list[str]) -> list[tuple[str, Any]]:
    from medax.cad import parts
    from medax.cad.reader import read_part
    from medax.cad.simplify import parts as sparts

    out: list[tuple[str, Any]] = []
    files = [Path(p) for p in paths] or [SHARED / n for n in STEP if (SHARED / n).is_file()]
    for p in files:
        out.append((p.name, read_part(p).solids[0]))
    if not paths:
        out.append(("box12 (26 faces)", sparts.box_all_fillets(40.0, 30.0, 20.0, 4.0).shape))
        out.append(("plate_with_boss", parts.plate_with_boss().shape))
        out.append(("stepped_shaft", parts.stepped_shaft().shape))
    return out


def _diagonal(shape: Any) -> float:
    from medax.cad.part_mesh import part_diagonal

    return part_diagonal(shape)


def _row(part: str, who: str, r: dict[str, Any]) -> str:
    if "error" in r:
        return f"{part:<24s} {who:<16s} {r['error']}"
    share = r["quads"] / max(r["n"], 1)
    p5 = f"{r['p5']:.3f}" if "p5" in r else "-"
    mn = f"{r['min']:.3f}" if "min" in r else "-"
    ang = f"{r['angle']:.1f}" if "angle" in r else "-"
    return (
        f"{part:<24s} {who:<16s} {r['n']:>8d} {100 * share:>6.1f}% {p5:>7s} {mn:>7s} "
        f"{ang:>6s} {r['time']:>8.2f} {r['cpu']:>7.2f} {r.get('faces', ''):>7s}"
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("parts", nargs="*", help="STEP/IGES/BRep files (default: shared + built)")
    ap.add_argument("--size", type=float, help="edge length (default: diagonal / --per)")
    ap.add_argument("--per", type=float, default=40.0, help="edges per diagonal (40)")
    ap.add_argument("--timeout", type=float, default=600.0, help="gmsh's limit, seconds")
    ap.add_argument("--no-simplify", action="store_true", help="skip medax after simplify")
    args = ap.parse_args()
    from OCP.BRepTools import BRepTools

    head = (
        f"{'part':<24s} {'mesher':<16s} {'elements':>8s} {'quads':>7s} {'SJ p5':>7s} "
        f"{'SJ min':>7s} {'angle':>6s} {'time s':>8s} {'cpu s':>7s} {'medial':>7s}"
    )
    print(head)
    print("-" * len(head))
    for name, shape in _parts(args.parts):
        size = args.size or _diagonal(shape) / args.per
        label = f"{name} h={size:.3g}"
        with tempfile.TemporaryDirectory() as tmp:
            brep = Path(tmp) / "part.brep"
            BRepTools.Write_s(shape, str(brep))
            gmsh_res = _gmsh(brep, size, args.timeout)
            print(_row(label, "gmsh", gmsh_res), flush=True)
        print(_row(label, "medax", _medax(shape, size)), flush=True)
        if not args.no_simplify:
            try:
                simple, t_s, c_s, faces = _simplified(shape)
            except Exception as err:  # (a part the simplification refuses: say so, go on)
                print(_row(label, "medax simplify", {"error": str(err)[:60]}))
                continue
            r = _medax(simple, size)
            extra = f"  (+{t_s:.1f} s simplify, cpu {c_s:.1f} s)"
            if "time" in r:  # (the whole --simplify run against gmsh, wall and CPU)
                g = gmsh_res.get("time"), gmsh_res.get("cpu")
                if g[0] and g[1]:
                    extra += (f"; with simplify / gmsh: {(r['time'] + t_s) / g[0]:.2f}x wall, "
                              f"{(r['cpu'] + c_s) / g[1]:.2f}x cpu")  # fmt: skip
            print(_row(label, f"medax simp {faces}", r) + extra, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
