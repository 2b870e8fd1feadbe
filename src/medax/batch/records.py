"""The records of a batch run: one JSON line per part in ``OUTDIR/records.jsonl``.

The file is a journal: a record is appended (one ``write`` of one whole line, then
``fsync``) as soon as its part is done, so an interrupted run loses only the parts in
flight, and a line cut short by a crash is ignored when the journal is read back. A later
record of the same part supersedes an earlier one. A part is *finished* when its record is
``ok`` or ``refused`` (medax's answer will not change) and the outputs it names still
exist; a new run skips finished parts whose bytes (SHA-256) and options are the same.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections import Counter
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from medax import __version__
from medax.errors import OutputError
from medax.io_utils import nonfinite_place

RECORDS = "records.jsonl"
#: the statuses of a part; the first two are final (skipped on resume)
STATUSES = ("ok", "refused", "failed", "timeout")
FINISHED = ("ok", "refused")
#: counts summed over the parts in the summary
COUNT_KEYS = (
    "faces",
    "fillets",
    "corner_blends",
    "axes",
    "faces_before",
    "faces_after",
    "blends_found",
    "blends_removed",
    "blends_kept",
    "mesh_quads",
)


def options_key(do: Iterable[str], options: Mapping[str, Any]) -> str:
    """16 hex characters identifying the work asked for: the steps, their options and
    medax's version (a new version reruns every part)."""
    text = json.dumps(
        {"do": list(do), "options": dict(options), "medax": __version__}, sort_keys=True
    )
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def read_records(outdir: str | Path) -> list[dict[str, Any]]:
    """The records of ``outdir/records.jsonl`` in order (none when it does not exist);
    lines that are not whole JSON objects (a crash mid-write) are skipped."""
    path = Path(outdir) / RECORDS
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return []
    out = []
    for line in text.splitlines():
        try:
            rec = json.loads(line)
        except ValueError:
            continue
        if isinstance(rec, dict) and "sha256" in rec and "options_key" in rec:
            out.append(rec)
    return out


def finished_records(outdir: str | Path) -> dict[tuple[str, str], dict[str, Any]]:
    """(sha256, options key) -> the latest record of a finished part whose outputs exist."""
    latest: dict[tuple[str, str], dict[str, Any]] = {}
    for rec in read_records(outdir):
        latest[(rec["sha256"], rec["options_key"])] = rec
    return {
        key: rec
        for key, rec in latest.items()
        if rec.get("status") in FINISHED
        and all(Path(outdir, p).is_file() for p in rec.get("outputs", {}).values())
    }


def append_record(outdir: str | Path, record: Mapping[str, Any]) -> None:
    """Append ``record`` as one line to ``outdir/records.jsonl`` (created when missing)."""
    path = Path(outdir) / RECORDS
    try:
        line = json.dumps(record, allow_nan=False, separators=(",", ":"))
    except ValueError:
        place = nonfinite_place(record) or "a value"
        raise OutputError(
            f"record of {record.get('input', '?')}: {place} is not a finite number"
        ) from None
    data = (line + "\n").encode("utf-8")
    try:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
        try:
            os.write(fd, data)
            os.fsync(fd)
        finally:
            os.close(fd)
    except OSError as err:
        raise OutputError(f"'{path}': cannot append a record ({err.strerror})") from None


def summarize(records: Iterable[Mapping[str, Any]], wall_s: float) -> dict[str, Any]:
    """Totals of a run: parts per status, summed counts, kept-blend reasons, times."""
    recs = list(records)
    status = Counter(str(r["status"]) for r in recs)
    totals: Counter[str] = Counter()
    reasons: Counter[str] = Counter()
    for r in recs:
        totals.update({k: int(v) for k, v in r.get("counts", {}).items() if k in COUNT_KEYS})
        reasons.update(r.get("kept_reasons", {}))
    skipped = sum(1 for r in recs if r.get("skipped"))
    run = [r for r in recs if not r.get("skipped")]
    return {
        "parts": len(recs),
        "skipped": skipped,
        "status": {s: status.get(s, 0) for s in STATUSES},
        "totals": {k: totals[k] for k in COUNT_KEYS if k in totals},
        "kept_reasons": dict(reasons.most_common()),
        "wall_s": round(wall_s, 3),
        "part_s": round(sum(float(r.get("time_s", 0.0)) for r in run), 3),
        "part_cpu_s": round(sum(float(r.get("cpu_s", 0.0)) for r in run), 3),
        "parts_per_min": round(60.0 * len(run) / wall_s, 2) if wall_s > 0 and run else 0.0,
    }
