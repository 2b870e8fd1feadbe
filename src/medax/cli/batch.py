"""``medax batch INPUTS... -o OUTDIR``: classify, simplify and mesh many parts on Dask."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from medax import tolerances
from medax.cli.options import check_tol


def add_parser(sub: argparse._SubParsersAction) -> None:
    from medax.batch.run import DEFAULT_TIMEOUT

    p = sub.add_parser(
        "batch",
        help="classify, simplify and mesh many parts, resumably, on a local or Dask cluster",
        description="Run 'medax classify', 'simplify' and 'mesh' on every part of INPUTS "
        "(files, folders searched recursively for .step/.stp/.brep, and glob patterns). Each "
        "part runs in its own process on a Dask worker: a local cluster of --workers "
        "processes, or the cluster of --scheduler. A part that takes longer than --timeout "
        "is killed and recorded as 'timeout'; a crash costs that part only. Outputs go to "
        "OUTDIR/<part>/ (classify.json, classified.step, simplified.step, simplify.json, "
        "the 3D view data, mesh.msh, mesh.json, the PNG views with --pictures, batch.log, "
        "report.html), the same files the single-part commands "
        "write; one JSON line per part is appended to OUTDIR/records.jsonl (status ok, "
        "refused, failed or timeout, counts, kept-blend reasons, times, outputs) and the "
        "totals to OUTDIR/summary.json, and OUTDIR/report.html shows them (one self-contained "
        "file: a sortable table, the kept-blend reasons, the pictures, an interactive 3D "
        "view of the parts, the mesh quality histograms). Run the same "
        "command again to resume: parts whose "
        "bytes and options match a finished record (ok or refused) are skipped. Progress "
        "(rate and time left) goes to stderr, a summary table to stdout. Exit code: 0 when "
        "every part is ok or refused, 3 when any part failed or timed out, 1 when the batch "
        "cannot start (bad option, no part found).",
        epilog="examples: medax batch parts/ -o out --do classify,simplify --workers 2; "
        "medax batch 'lib/**/*.step' -o out --do classify,simplify,mesh --mesh-size 2 "
        "--scheduler tcp://10.0.0.5:8786 --timeout 300",
    )
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="part files, folders or globs")
    p.add_argument("-o", "--outdir", required=True, help="output folder (created if missing)")
    p.add_argument(
        "--do",
        default="classify,simplify",
        help="steps, comma-separated, among classify, simplify, mesh (default classify,simplify)",
    )
    p.add_argument(
        "--workers", type=int, help="local worker processes (default: the number of CPUs)"
    )
    p.add_argument(
        "--scheduler",
        help="address of a running Dask scheduler (tcp://host:port) instead of a local "
        "cluster; its workers need medax installed (with DASK_DISTRIBUTED__WORKER__DAEMON="
        "False they fork each part from a warm process, else each part imports OCP anew)",
    )
    p.add_argument(
        "--timeout",
        type=float,
        default=DEFAULT_TIMEOUT,
        help=f"seconds per part before its process is killed (default {DEFAULT_TIMEOUT:g}; "
        "0: no limit)",
    )
    p.add_argument(
        "--angle",
        type=float,
        default=tolerances.TANGENT_ANGLE,
        help=f"classify: tangency tolerance, radians (default {tolerances.TANGENT_ANGLE:g})",
    )
    p.add_argument(
        "--tol",
        type=float,
        default=tolerances.CURVE_TOL,
        help=f"classify: axis curve tolerance x diagonal (default {tolerances.CURVE_TOL:g})",
    )
    p.add_argument(
        "--simplify-tol", type=float, default=1e-5, help="simplify: deviation tolerance (1e-5)"
    )
    p.add_argument(
        "--strict-volume",
        action="store_true",
        help="simplify: keep the fillets whose merged faces OCCT's default mass properties "
        "would misread (see 'medax simplify --help')",
    )
    p.add_argument("--mesh-size", type=float, help="mesh: target edge length (model units)")
    p.add_argument("--pictures", action="store_true", help="also write each step's PNG view")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from medax.batch.run import BatchOptions, run_batch

    do = tuple(s.strip() for s in args.do.split(",") if s.strip())
    # refused here, before any part runs (each part's own command would refuse it too)
    check_tol(args.tol, "--tol", tolerances.MIN_CURVE_TOL)
    check_tol(args.simplify_tol, "--simplify-tol", tolerances.BUILD_TOL)
    check_tol(args.timeout, "--timeout", 0.0, zero_ok=True)
    opts = BatchOptions(
        do=do,
        workers=args.workers,
        scheduler=args.scheduler,
        timeout=args.timeout or None,
        angle=args.angle,
        tol=args.tol,
        simplify_tol=args.simplify_tol,
        strict_volume=args.strict_volume,
        mesh_size=args.mesh_size,
        pictures=args.pictures,
    )
    try:
        result = run_batch(args.inputs, args.outdir, opts, progress=ProgressLine())
    except KeyboardInterrupt as err:  # the records of finished parts are kept: say so
        from medax.cli.main import Terminated

        what = "terminated" if isinstance(err, Terminated) else "interrupted"
        print(
            f"\nmedax batch: {what}; the finished parts are in "
            f"{Path(args.outdir) / 'records.jsonl'}: run the same command to resume",
            file=sys.stderr,
        )
        return 143 if isinstance(err, Terminated) else 130
    for line in summary_table(result.summary, result.records):
        print(line)
    for name in ("records.jsonl", "summary.json", "report.html"):
        print(f"wrote {result.outdir / name}")
    return result.exit_code


class ProgressLine:
    """One progress line per part on stderr (rewritten in place on a terminal)."""

    def __init__(self) -> None:
        self.tty = sys.stderr.isatty()

    def __call__(self, p: Any) -> None:
        st = p.status
        eta = "-" if p.eta_s is None else _duration(p.eta_s)
        rec = p.record
        line = (
            f"[{p.done}/{p.total}] {100.0 * p.done / p.total:3.0f}%  "
            f"{p.rate_per_min:.1f} parts/min  ETA {eta}  "
            f"ok {st.get('ok', 0)} refused {st.get('refused', 0)} "
            f"failed {st.get('failed', 0)} timeout {st.get('timeout', 0)}  "
            f"{rec['part_dir']}: {rec['status']}"
        )
        if self.tty:
            end = "\n" if p.done == p.total else ""
            print(f"\r\033[K{line}", end=end, file=sys.stderr, flush=True)
        else:
            print(line, file=sys.stderr, flush=True)


#: parts listed one per row at the end of a run; above it, only the parts not ok
MAX_ROWS = 40


def summary_table(summary: dict[str, Any], records: list[dict[str, Any]]) -> list[str]:
    """The end-of-run table: one row per part, then the totals."""
    rows = [("part", "status", "faces", "after", "blends", "removed", "kept", "time s")]
    listed = [r for r in records if len(records) <= MAX_ROWS or r["status"] != "ok"]
    for r in listed:
        c = r.get("counts", {})
        rows.append(
            (
                str(r["part_dir"]),
                str(r["status"]) + (" (skipped)" if r.get("skipped") else ""),
                str(c.get("faces", c.get("faces_before", "-"))),
                str(c.get("faces_after", "-")),
                str(c.get("blends_found", c.get("fillets", "-"))),
                str(c.get("blends_removed", "-")),
                str(c.get("blends_kept", "-")),
                f"{r.get('time_s', 0.0):.1f}",
            )
        )
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    lines = ["  ".join(v.ljust(w) for v, w in zip(row, widths, strict=True)) for row in rows]
    lines.insert(1, "  ".join("-" * w for w in widths))
    st, tot = summary["status"], summary["totals"]
    if len(listed) < len(records):
        lines.append(f"({len(records) - len(listed)} ok parts not listed: see report.html)")
    lines.append("")
    lines.append(
        f"{summary['parts']} parts ({summary['skipped']} skipped as finished): "
        f"ok {st['ok']}, refused {st['refused']}, failed {st['failed']}, "
        f"timeout {st['timeout']}"
    )
    if "faces_before" in tot:
        lines.append(
            f"faces {tot['faces_before']} -> {tot.get('faces_after', 0)}; blends "
            f"{tot.get('blends_found', 0)} found, {tot.get('blends_removed', 0)} removed, "
            f"{tot.get('blends_kept', 0)} kept"
        )
    if summary["kept_reasons"]:
        reasons = ", ".join(f"{k} {v}" for k, v in summary["kept_reasons"].items())
        lines.append(f"kept because: {reasons}")
    for r in records:
        if r["status"] not in ("ok",) and r.get("error"):
            lines.append(f"{r['part_dir']}: {r['status']}: {r['error']}")
    lines.append(
        f"wall {_duration(summary['wall_s'])}, {summary['parts_per_min']:.1f} parts/min, "
        f"{summary['part_s']:.1f} s of part processes"
    )
    return lines


def _duration(s: float) -> str:
    s = max(0.0, s)
    if s < 60:
        return f"{s:.0f}s"
    if s < 3600:
        return f"{int(s // 60)}m{int(s % 60):02d}s"
    return f"{int(s // 3600)}h{int(s % 3600 // 60):02d}m"
