"""``medax batch`` throughput on a folder of parts: parts per minute on 1 and 2 Dask
workers, the overhead per part against the same work in one process, and the speed-up.

The reference runs the same subcommands (``medax classify``/``simplify`` in-process, the
same outputs) one part after another in one fresh Python process, import included. Each
batch run starts its own LocalCluster (``--workers N``) in a fresh output folder, and its
wall time includes the cluster's start and each worker's fork server (medax and OCP
imported once per worker). Overhead per part = (batch wall on 1 worker - reference wall) /
parts.

    .venv/bin/python benchmarks/bench_batch.py ../shared/bench/cad/corpus --limit 15 \\
        --do classify [--workers 1,2] [--json out.json]
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

PARTS = (".step", ".stp", ".brep")

#: the reference: every part's steps in one process, as the batch's child runs them
REFERENCE = """
import json, os, sys, time
t0 = time.perf_counter()
from medax.batch.part import PartTask, work
paths, do, out = json.loads(sys.argv[1]), tuple(sys.argv[2].split(",")), sys.argv[3]
opts = json.loads(sys.argv[4])
status = {}
for i, p in enumerate(paths):
    os.makedirs(os.path.join(out, f"p{i}"))
    rec = work(PartTask(p, "0" * 64, "0" * 16, out, f"p{i}", do, opts))
    status[rec["status"]] = status.get(rec["status"], 0) + 1
print(json.dumps({"wall_s": time.perf_counter() - t0, "status": status}))
"""


def pick(folder: Path, limit: int | None, files: Path | None) -> list[Path]:
    """The parts: those listed in ``files`` (one path a line), else the ``limit`` smallest
    of ``folder`` (all when None)."""
    if files is not None:
        lines = files.read_text().splitlines()
        return [Path(s.strip()) for s in lines if s.strip() and not s.startswith("#")]
    parts = sorted(
        (p for p in folder.rglob("*") if p.suffix.lower() in PARTS),
        key=lambda p: (p.stat().st_size, p.name),
    )
    return parts[:limit] if limit else parts


def reference(parts: list[Path], do: tuple[str, ...], opts: dict[str, Any]) -> dict[str, Any]:
    """Wall time of the parts run one after another in one fresh process."""
    with tempfile.TemporaryDirectory() as out:
        argv = [json.dumps([str(p) for p in parts]), ",".join(do), out, json.dumps(opts)]
        proc = subprocess.run(
            [sys.executable, "-c", REFERENCE, *argv],
            capture_output=True,
            text=True,
            check=True,
        )
    result: dict[str, Any] = json.loads(proc.stdout.strip().splitlines()[-1])
    return result


def batch(parts: list[Path], do: tuple[str, ...], workers: int, timeout: float) -> dict[str, Any]:
    """Wall time of ``run_batch`` on a LocalCluster of ``workers`` processes."""
    from medax.batch import BatchOptions, run_batch

    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        res = run_batch(
            [str(p) for p in parts],
            Path(out),
            BatchOptions(do=do, workers=workers, timeout=timeout),
        )
        wall = time.perf_counter() - t0
    part_s = sum(r["time_s"] for r in res.records)
    return {"wall_s": wall, "status": res.summary["status"], "part_s": part_s}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", type=Path, help="folder of parts")
    ap.add_argument("--limit", type=int, help="the N smallest parts (by file size)")
    ap.add_argument("--files", type=Path, help="a list of part paths, one a line")
    ap.add_argument("--do", default="classify", help="steps (default classify)")
    ap.add_argument("--workers", default="1,2", help="worker counts to run (default 1,2)")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per part")
    ap.add_argument("--json", type=Path, help="write the numbers as JSON")
    args = ap.parse_args(argv)
    from medax.batch import BatchOptions

    parts = pick(args.folder, args.limit, args.files)
    do = tuple(args.do.split(","))
    opts = BatchOptions(do=do).step_options()
    n = len(parts)
    kb = sum(p.stat().st_size for p in parts) / 1024
    print(f"{n} parts ({kb:.0f} KiB), --do {args.do}", flush=True)
    ref = reference(parts, do, opts)
    print(f"one process, sequential: {ref['wall_s']:.1f} s {ref['status']}", flush=True)
    rows = [("one process", 1, ref["wall_s"], None)]
    runs: dict[int, dict[str, Any]] = {}
    for w in (int(x) for x in args.workers.split(",")):
        runs[w] = batch(parts, do, w, args.timeout)
        print(f"batch, {w} worker(s): {runs[w]['wall_s']:.1f} s {runs[w]['status']}", flush=True)
        rows.append((f"medax batch, {w} worker{'s' if w > 1 else ''}", w, runs[w]["wall_s"], w))
    print()
    print("| run | wall s | parts/min | overhead s/part vs one process | speed-up vs 1 worker |")
    print("|---|---:|---:|---:|---:|")
    one = runs.get(1)
    for label, _, wall, w in rows:
        over = "" if w is None else f"{(wall - ref['wall_s']) / n:+.2f}"
        speed = "" if w is None or one is None else f"{one['wall_s'] / wall:.2f}"
        print(f"| {label} | {wall:.1f} | {60.0 * n / wall:.1f} | {over} | {speed} |")
    if args.json is not None:
        data = {"parts": [str(p) for p in parts], "do": do, "reference": ref, "batch": runs}
        args.json.write_text(json.dumps(data, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
