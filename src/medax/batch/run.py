"""The client side of a batch: find the parts, skip the finished ones, send the others to
Dask, journal the records as they come back and sum them up.

By default a :class:`distributed.LocalCluster` of worker processes (one thread each) is
started on 127.0.0.1 for the run; ``scheduler`` names an existing cluster instead. A worker
that dies while running a part is replaced by its nanny and the part is run once more on a
local cluster (``allowed-failures`` 1); when it dies again the part is recorded as failed.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from medax import tolerances
from medax.batch.inputs import collect_inputs, file_sha256, part_dirs
from medax.batch.part import (
    STEPS,
    PartTask,
    base_record,
    finish,
    one_line,
    run_part,
    tolerances_of,
)
from medax.batch.records import (
    FINISHED,
    append_record,
    finished_records,
    options_key,
    summarize,
)
from medax.errors import InputError

log = logging.getLogger(__name__)

SUMMARY = "summary.json"
LOCK = ".medax-batch.lock"
#: seconds between checks that a local cluster still has its workers
REVIVE_EVERY_S = 5.0
#: seconds a part may take by default before its process is killed
DEFAULT_TIMEOUT = 900.0


@dataclass(frozen=True)
class BatchOptions:
    """What to do with every part and where to run it.

    ``do``: steps among ``classify``, ``simplify``, ``mesh`` (run in that order; the mesh is
    made on the simplified part when simplify runs). ``workers``: local worker processes
    (default: the CPU count). ``scheduler``: ``tcp://host:port`` of a running Dask
    scheduler (then ``workers`` is ignored). ``timeout``: seconds per part (None: no
    limit). ``angle``, ``tol``: classify's; ``simplify_tol``: simplify's ``--tol``;
    ``strict_volume``: simplify's ``--strict-volume``;
    ``mesh_size``: the mesh's ``--size`` (model units, needed for ``mesh``); ``pictures``:
    also write the PNG views. ``hook``: ``"module:function"`` called with each part's path
    in its process before the work (for tests)."""

    do: tuple[str, ...] = ("classify", "simplify")
    workers: int | None = None
    scheduler: str | None = None
    timeout: float | None = DEFAULT_TIMEOUT
    angle: float = tolerances.TANGENT_ANGLE
    tol: float = tolerances.CURVE_TOL
    simplify_tol: float = 1e-5
    strict_volume: bool = False
    mesh_size: float | None = None
    pictures: bool = False
    hook: str | None = None

    def step_options(self) -> dict[str, Any]:
        """The options the steps see (and that decide whether a record can be reused)."""
        opts: dict[str, Any] = {"pictures": self.pictures}
        if "classify" in self.do:
            opts.update(angle=self.angle, tol=self.tol)
        if "simplify" in self.do:
            opts["simplify_tol"] = self.simplify_tol
            if self.strict_volume:  # (absent when off: the records of before stay valid)
                opts["strict_volume"] = True
        if "mesh" in self.do:
            opts["mesh_size"] = self.mesh_size
        return opts

    def check(self) -> None:
        """:class:`InputError` for options that cannot work, before any part is run."""
        if not self.do or any(s not in STEPS for s in self.do):
            raise InputError(f"--do must list steps among {', '.join(STEPS)}, got {self.do}")
        if len(set(self.do)) != len(self.do):
            raise InputError(f"--do names a step twice: {','.join(self.do)}")
        if "mesh" in self.do and not _positive(self.mesh_size):
            raise InputError("--do mesh needs --mesh-size (a positive edge length, model units)")
        if self.timeout is not None and not _positive(self.timeout):
            raise InputError(f"--timeout must be a positive number of seconds, got {self.timeout}")
        if self.workers is not None and self.workers < 1:
            raise InputError(f"--workers must be at least 1, got {self.workers}")
        if not (_positive(self.angle) and _positive(self.tol) and _positive(self.simplify_tol)):
            raise InputError("--angle, --tol and --simplify-tol must be positive numbers")
        if self.scheduler is not None and "://" not in self.scheduler:
            raise InputError(
                f"--scheduler '{self.scheduler}': give an address such as tcp://host:8786"
            )


@dataclass(frozen=True)
class Progress:
    """The state of a run after one more part: ``done`` of ``total`` parts to run (skipped
    parts excluded), parts per status so far, seconds since the first part was sent, and
    the record just received."""

    done: int
    total: int
    status: dict[str, int]
    elapsed_s: float
    record: dict[str, Any]

    @property
    def rate_per_min(self) -> float:
        """Parts finished per minute so far."""
        return 60.0 * self.done / self.elapsed_s if self.elapsed_s > 0 else 0.0

    @property
    def eta_s(self) -> float | None:
        """Seconds left at the current rate (None before the first part)."""
        return self.elapsed_s / self.done * (self.total - self.done) if self.done else None


@dataclass
class BatchResult:
    """The records of every part (skipped ones with ``skipped: true``) and the summary."""

    records: list[dict[str, Any]]
    summary: dict[str, Any]
    outdir: Path = field(default_factory=Path)

    @property
    def exit_code(self) -> int:
        """0 when every part is ok or refused, 3 when any failed or timed out."""
        bad = {r["status"] for r in self.records} - set(FINISHED)
        return 3 if bad else 0


def run_batch(
    inputs: Sequence[str],
    outdir: str | Path,
    options: BatchOptions | None = None,
    progress: Callable[[Progress], None] | None = None,
) -> BatchResult:
    """Run ``options.do`` on every part of ``inputs`` (files, folders, globs), outputs in
    ``outdir/<part>/``, records in ``outdir/records.jsonl``; returns the records and the
    summary (also written to ``outdir/summary.json``, and with the records to
    ``outdir/report.html``). Parts already finished with the same
    bytes and options are skipped. :class:`InputError` before any work for bad options."""
    opts = options or BatchOptions()
    opts.check()
    out = _output_folder(outdir)
    with _lock(out):
        return _run_locked(inputs, out, opts, progress)


def _run_locked(
    inputs: Sequence[str],
    out: Path,
    opts: BatchOptions,
    progress: Callable[[Progress], None] | None,
) -> BatchResult:
    from medax.batch.html import write_report
    from medax.io_utils import write_json
    from medax.schemas import stamp

    paths = collect_inputs(inputs, exclude=out)
    hashes = [file_sha256(p) for p in paths]
    step_opts = opts.step_options()
    key = options_key(opts.do, step_opts)
    done = finished_records(out)
    records: list[dict[str, Any]] = []
    tasks: list[PartTask] = []
    for path, sha, folder in zip(paths, hashes, part_dirs(paths, hashes), strict=True):
        old = done.get((sha, key))
        if old is not None:
            records.append(dict(old, input=os.path.abspath(path), skipped=True))
            continue
        task = PartTask(
            path=os.path.abspath(path),  # the workers' working folder may differ
            sha256=sha,
            options_key=key,
            outdir=os.path.abspath(out),
            part_dir=folder,
            do=opts.do,
            options=step_opts,
            timeout=opts.timeout,
            hook=opts.hook,
        )
        tasks.append(task)
    log.info("%d parts: %d to run, %d finished before", len(paths), len(tasks), len(records))
    start = time.perf_counter()
    if tasks:
        for rec in _run_tasks(tasks, opts, start, progress):
            append_record(out, rec)
            records.append(rec)
    wall = time.perf_counter() - start
    summary = summarize(records, wall)
    units = {r["units"]["length"] for r in records if r["units"]["length"] != "unspecified"}
    data = {"do": list(opts.do), "options": step_opts} | summary
    unit = units.pop() if len(units) == 1 else ("mixed" if units else "unspecified")
    stamped = stamp("batch-summary", data, unit, tolerances_of(step_opts), time="s")
    write_json(out / SUMMARY, stamped, "summary")
    write_report(records, summary, out)
    return BatchResult(records, summary, out)


def _run_tasks(
    tasks: list[PartTask],
    opts: BatchOptions,
    start: float,
    progress: Callable[[Progress], None] | None,
) -> Iterator[dict[str, Any]]:
    """Send ``tasks`` to Dask and yield each record as it arrives."""
    from distributed import as_completed

    counts = {"ok": 0, "refused": 0, "failed": 0, "timeout": 0}
    with _client(opts) as client:
        # the largest files first, so that a long part does not start last and run alone
        order = sorted(tasks, key=lambda t: -_size(t.path))
        futures = [
            client.submit(
                run_part,
                t,
                key=f"medax-part-{t.part_dir}-{t.sha256[:8]}-{t.options_key[:8]}",
                pure=False,
                priority=len(order) - i,
            )
            for i, t in enumerate(order)
        ]
        task_of = {f.key: t for f, t in zip(futures, order, strict=True)}
        local = client.cluster if opts.scheduler is None else None
        done = as_completed(futures)
        n = 0
        checked = time.monotonic()
        while not done.is_empty():
            if not done.has_ready():
                time.sleep(0.05)
                if local is not None and time.monotonic() - checked > REVIVE_EVERY_S:
                    checked = time.monotonic()
                    revive_local_workers(local)
                continue
            for fut in done.next_batch(block=False):
                n += 1
                rec = _record(fut, task_of[fut.key])
                counts[rec["status"]] = counts.get(rec["status"], 0) + 1
                if progress is not None:
                    elapsed = time.perf_counter() - start
                    progress(Progress(n, len(tasks), dict(counts), elapsed, rec))
                yield rec


def revive_local_workers(cluster: Any) -> int:
    """Start anew the workers of a local cluster whose nanny has stopped (a nanny closes
    itself when it fails to restart a worker that died); how many were started."""
    from distributed.core import Status

    try:
        dead = [
            name
            for name, w in list(cluster.workers.items())
            if getattr(w, "status", None) in (Status.closed, Status.failed)
        ]
        if dead:
            for name in dead:
                cluster.workers.pop(name, None)
            cluster.scale(len(cluster.worker_spec))
            log.warning("started %d local Dask workers again (their nanny had stopped)", len(dead))
        return len(dead)
    except Exception as err:  # a watchdog: never the reason a run stops
        log.warning("could not check the local Dask workers: %s", err)
        return 0


def _record(fut: Any, task: PartTask) -> dict[str, Any]:
    """The future's record, or a ``failed`` one when the task raised (a worker that died
    twice running it: ``KilledWorker``) or was cancelled."""
    import asyncio

    from distributed import KilledWorker

    try:
        rec: dict[str, Any] = fut.result()
        return rec
    except KilledWorker:
        msg = "the Dask workers running it died (KilledWorker); see the workers' logs"
    except (Exception, asyncio.CancelledError) as err:
        msg = f"the task raised {one_line(err)}"
    rec = finish(base_record(task), "failed", time.perf_counter(), msg)
    rec["time_s"] = 0.0
    return rec


@contextlib.contextmanager
def _client(opts: BatchOptions) -> Iterator[Any]:
    """A Dask client on ``opts.scheduler`` or on a local cluster started for the run."""
    with _quiet_dask():
        yield from _client_of(opts)


@contextlib.contextmanager
def _quiet_dask() -> Iterator[None]:
    """Dask's own INFO lines (scheduler, nannies) only when medax logs at DEBUG."""
    loggers = [logging.getLogger(n) for n in ("distributed", "dask")]
    levels = [lg.level for lg in loggers]
    if not logging.getLogger().isEnabledFor(logging.DEBUG):
        for lg in loggers:
            lg.setLevel(logging.WARNING)
    try:
        yield
    finally:
        for lg, level in zip(loggers, levels, strict=True):
            lg.setLevel(level)


def _client_of(opts: BatchOptions) -> Iterator[Any]:
    import dask
    from distributed import Client, LocalCluster

    if opts.scheduler is not None:
        try:
            client = Client(opts.scheduler, timeout="20s")
        except OSError as err:
            raise InputError(f"--scheduler {opts.scheduler}: cannot connect ({err})") from None
        with client:
            yield client
        return
    workers = opts.workers or os.cpu_count() or 1
    config = {
        "distributed.worker.daemon": False,  # the workers start a process per part
        "distributed.scheduler.allowed-failures": 1,  # a part that kills its worker: retry once
    }
    with dask.config.set(config):
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address="127.0.0.1:0",  # no fixed port: other clusters may run here
            silence_logs=logging.ERROR,
        )
        with cluster, Client(cluster) as client:
            yield client


@contextlib.contextmanager
def _lock(out: Path) -> Iterator[None]:
    """Hold ``out/.medax-batch.lock`` (flock) for the run: :class:`InputError` when another
    batch is writing to the same folder."""
    import fcntl

    fd = os.open(out / LOCK, os.O_WRONLY | os.O_CREAT, 0o666)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise InputError(f"-o '{out}': another medax batch is writing to it") from None
        yield
    finally:
        os.close(fd)


def _output_folder(outdir: str | Path) -> Path:
    out = Path(outdir)
    if out.exists() and not out.is_dir():
        raise InputError(f"-o '{out}': is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputError(f"-o '{out}': cannot create the folder ({err.strerror})") from None
    if not os.access(out, os.W_OK | os.X_OK):
        raise InputError(f"-o '{out}': the folder is not writable")
    return out


def _size(path: str) -> int:
    try:
        return os.path.getsize(path)
    except OSError:
        return 0


def _positive(x: float | None) -> bool:
    return x is not None and math.isfinite(x) and x > 0.0
