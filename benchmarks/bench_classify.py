"""Fillet classification time as a ratio to the STEP read time of the same file.

Peer, measured in the same run: OCCT's own STEP reader (``STEPControl_Reader`` ReadFile +
TransferRoots). Parts: the shared STEP parts (``--shared``, default
``../shared/bench/cad`` when present) and a generated plate with a 12 x 12 grid of filleted
bosses (580+ faces) written to STEP first; with ``--corpus DIR`` every part of a folder (``.brep``
parts written to STEP first, so the peer is always the STEP read), then the totals. Each
time is the median of ``--repeat`` runs. Target: classification (with ``--axes``, the
fillet axes too) no slower than reading (ratio <= 1).

    python benchmarks/bench_classify.py [--repeat 3] [--shared DIR] [--axes]
    python benchmarks/bench_classify.py --corpus ../shared/bench/cad/corpus --axes --repeat 1
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from medax.cad import parts
from medax.cad.classify import classify_solid
from medax.cad.reader import heal, quiet_occt, read_part
from medax.cad.report import trace_fillet_axes
from medax.cad.simplify.step_out import write_step


def occt_read(path: Path) -> Any:
    from OCP.STEPControl import STEPControl_Reader

    with quiet_occt():
        r = STEPControl_Reader()
        r.ReadFile(str(path))
        r.TransferRoots()
        return r.OneShape()


def brep_shape(path: Path) -> Any:
    from OCP.BRep import BRep_Builder
    from OCP.BRepTools import BRepTools
    from OCP.TopoDS import TopoDS_Shape

    shape = TopoDS_Shape()
    if not BRepTools.Read_s(shape, str(path), BRep_Builder()):
        raise RuntimeError(f"{path}: not a readable BRep file")
    return shape


def median_time(fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def bench(path: Path, repeat: int, axes: bool) -> tuple[float, float]:
    """Print one part's line; (read time, classify time with the axes when ``axes``), s."""
    t_read, _ = median_time(lambda: occt_read(path), repeat)
    part = read_part(path)
    t_heal, _ = median_time(lambda: [heal(s) for s in part.solids], repeat)
    t_cls, cs = median_time(lambda: [classify_solid(s) for s in part.solids], repeat)
    faces = sum(c.counts()["faces"] for c in cs)
    blends = sum(len(c.blends) for c in cs)
    line = (
        f"{path.name:28s} {faces:5d} faces {blends:4d} blends | read {t_read * 1e3:8.1f} ms "
        f"heal {t_heal * 1e3:8.1f} ms classify {t_cls * 1e3:8.1f} ms | "
        f"classify/read {t_cls / t_read:5.2f}"
    )
    t_ax = 0.0
    if axes:
        t_ax, _ = median_time(lambda: [trace_fillet_axes(c) for c in cs], 1)
        n = sum(len(c.fillets) for c in cs)
        line += f" | {n} axes {t_ax * 1e3:8.1f} ms | (classify + axes)/read "
        line += f"{(t_cls + t_ax) / t_read:5.2f}"
    print(line, flush=True)
    return t_read, t_cls + t_ax


def corpus(folder: Path, repeat: int, axes: bool) -> None:
    """Every part of ``folder`` (``.brep`` ones written to STEP first), then the totals."""
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() in (".step", ".stp", ".brep"))
    total_read = total_cls = 0.0
    with tempfile.TemporaryDirectory() as tmp:
        for f in files:
            step = f
            if f.suffix.lower() == ".brep":
                step = write_step(brep_shape(f), Path(tmp) / (f.stem + ".step"))
            try:
                t_read, t_cls = bench(step, repeat, axes)
            except Exception as err:  # a part the reader refuses: named, the run goes on
                print(f"{f.name:28s} refused: {type(err).__name__}: {err}", flush=True)
                continue
            total_read += t_read
            total_cls += t_cls
    what = "classify + axes" if axes else "classify"
    print(
        f"total: read {total_read:.1f} s, {what} {total_cls:.1f} s, "
        f"ratio {total_cls / max(total_read, 1e-12):.2f}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--shared", default=str(Path(__file__).parents[2] / "shared/bench/cad"))
    ap.add_argument("--axes", action="store_true", help="also time tracing every fillet axis")
    ap.add_argument("--corpus", help="a folder of parts (.step/.stp/.brep): each, then totals")
    args = ap.parse_args()
    if args.corpus:
        corpus(Path(args.corpus), args.repeat, args.axes)
        return
    files = sorted(Path(args.shared).glob("*.st*p")) if Path(args.shared).is_dir() else []
    print("classification time / OCCT STEP read time (median of", args.repeat, "runs)")
    for f in files:
        bench(f, args.repeat, args.axes)
    with tempfile.TemporaryDirectory() as tmp:
        built = parts.boss_grid(12)
        step = write_step(built.shape, Path(tmp) / "boss_grid_12.step")
        bench(step, args.repeat, args.axes)


if __name__ == "__main__":
    main()
