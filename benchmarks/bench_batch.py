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
import os
import resource
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
    """Wall and CPU time of the parts run one after another in one fresh process."""
    cpu0 = _children_cpu()
    with tempfile.TemporaryDirectory() as out:
        argv = [json.dumps([str(p) for p in parts]), ",".join(do), out, json.dumps(opts)]
        proc = subprocess.run(
            [sys.executable, "-c", REFERENCE, *argv],
            capture_output=True,
            text=True,
            check=True,
        )
    result: dict[str, Any] = json.loads(proc.stdout.strip().splitlines()[-1])
    result["cpu_s"] = _children_cpu() - cpu0
    return result


def _children_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


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
    s = res.summary
    # per part on the worker: the fork, the pipe and the record, around the work itself
    extra = sorted(r["wall_s"] - r["time_s"] for r in res.records if "wall_s" in r)
    return {
        "wall_s": wall,
        "status": s["status"],
        "part_s": s["part_s"],
        "cpu_s": s["part_cpu_s"],
        "process_overhead_median_s": extra[len(extra) // 2] if extra else None,
    }


#: about a second of pure Python CPU
SPIN = "s = 0\nfor i in range(12_000_000):\n    s += i"


def parallel_capacity(n: int = 2) -> float:
    """How much faster ``n`` processes of pure CPU run side by side than one after another:
    about ``n`` on an idle machine with ``n`` free cores, about 1 when the cores are busy."""
    t0 = time.perf_counter()
    for _ in range(n):
        subprocess.run([sys.executable, "-c", SPIN], check=True)
    serial = time.perf_counter() - t0
    t0 = time.perf_counter()
    procs = [subprocess.Popen([sys.executable, "-c", SPIN]) for _ in range(n)]
    for p in procs:
        p.wait()
    return serial / (time.perf_counter() - t0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", type=Path, help="folder of parts")
    ap.add_argument("--limit", type=int, help="the N smallest parts (by file size)")
    ap.add_argument("--files", type=Path, help="a list of part paths, one a line")
    ap.add_argument("--do", default="classify", help="steps (default classify)")
    ap.add_argument("--workers", default="1,2", help="worker counts to run (default 1,2)")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per part")
    ap.add_argument("--repeat", type=int, default=1, help="runs of each kind; best kept")
    ap.add_argument("--json", type=Path, help="write the numbers as JSON")
    args = ap.parse_args(argv)
    from medax.batch import BatchOptions

    parts = pick(args.folder, args.limit, args.files)
    do = tuple(args.do.split(","))
    opts = BatchOptions(do=do).step_options()
    n = len(parts)
    kb = sum(p.stat().st_size for p in parts) / 1024
    print(f"{n} parts ({kb:.0f} KiB), --do {args.do}", flush=True)
    counts = [int(x) for x in args.workers.split(",")]
    refs: list[dict[str, Any]] = []
    runs: dict[int, list[dict[str, Any]]] = {w: [] for w in counts}
    capacity = []
    for k in range(args.repeat):  # alternated, so that other loads hit every kind alike
        capacity.append(parallel_capacity(2))
        print(f"[{k + 1}] 2 CPU-bound processes side by side: {capacity[-1]:.2f}x one by one")
        refs.append(reference(parts, do, opts) | {"load": os.getloadavg()[0]})
        print(f"[{k + 1}] one process: {refs[-1]['wall_s']:.1f} s {refs[-1]['status']}")
        for w in counts:
            runs[w].append(batch(parts, do, w, args.timeout) | {"load": os.getloadavg()[0]})
            r = runs[w][-1]
            print(f"[{k + 1}] batch, {w} worker(s): {r['wall_s']:.1f} s {r['status']}", flush=True)
    ref = min(refs, key=lambda r: r["wall_s"])
    best = {w: min(rs, key=lambda r: r["wall_s"]) for w, rs in runs.items()}
    print()
    print(
        "| run | wall s | parts/min | CPU s of the parts | overhead s/part vs one process "
        "| speed-up vs 1 worker | process per part, median s | load avg |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    print(
        f"| one process, sequential | {ref['wall_s']:.1f} | {60.0 * n / ref['wall_s']:.1f} "
        f"| {ref['cpu_s']:.1f} (with the import) | | | | {ref['load']:.1f} |"
    )
    for w, r in best.items():
        over = (r["wall_s"] - ref["wall_s"]) / n
        speed = f"{best[1]['wall_s'] / r['wall_s']:.2f}" if 1 in best else ""
        label = f"medax batch, {w} worker{'s' if w > 1 else ''}"
        print(
            f"| {label} | {r['wall_s']:.1f} | {60.0 * n / r['wall_s']:.1f} | {r['cpu_s']:.1f} "
            f"| {over:+.2f} | {speed} | {r['process_overhead_median_s']:.3f} | {r['load']:.1f} |"
        )
    caps = ", ".join(f"{c:.2f}x" for c in capacity)
    print(f"\nthe machine's parallel capacity (2 pure-CPU processes side by side): {caps}")
    if args.json is not None:
        data = {"parts": [str(p) for p in parts], "do": do, "reference": refs, "batch": runs}
        data["parallel_capacity"] = capacity
        args.json.write_text(json.dumps(data, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
