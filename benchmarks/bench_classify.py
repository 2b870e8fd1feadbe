"""Fillet classification time as a ratio to the STEP read time of the same file.

Peer, measured in the same run: OCCT's own STEP reader (``STEPControl_Reader`` ReadFile +
TransferRoots). Parts: the shared STEP parts (``--shared``, default
``../shared/bench/cad`` when present) and a generated plate with a 12 x 12 grid of filleted
bosses (580+ faces) written to STEP first. Each time is the median of ``--repeat`` runs.
Target: classification no slower than reading (ratio <= 1).

    python benchmarks/bench_classify.py [--repeat 3] [--shared DIR] [--axes]
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


def median_time(fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def bench(path: Path, repeat: int, axes: bool) -> None:
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
    if axes:
        t_ax, _ = median_time(lambda: [trace_fillet_axes(c) for c in cs], 1)
        n = sum(len(c.fillets) for c in cs)
        line += f" | {n} axes {t_ax * 1e3:8.1f} ms ({t_ax / t_read:5.2f} x read)"
    print(line, flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--shared", default=str(Path(__file__).parents[2] / "shared/bench/cad"))
    ap.add_argument("--axes", action="store_true", help="also time tracing every fillet axis")
    args = ap.parse_args()
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
