"""One part of a batch: the Dask task and the child process that does the work.

:func:`run_part` runs on a Dask worker. It forks a child from a per-worker fork server that
has medax and OCP imported already (so a part costs a fork, not a 2.5 s interpreter start),
waits for the child's record at most ``timeout`` seconds and kills it (SIGKILL, which stops
any OCCT call) when it is late, removing the temporaries its outputs left. The child runs
the asked steps as the ``medax`` subcommands do (``medax classify/simplify/mesh``, parsed and
run in-process), with its stdout and stderr in the part's ``batch.log``, and returns a
JSON-able record: shapes never leave the child. A daemonic worker (a stock ``dask worker``)
may not have ``multiprocessing`` children: there the part runs in a new interpreter
(``python -m medax.batch.child``), with the same timeout and kill.
"""

from __future__ import annotations

import contextlib
import importlib
import json
import multiprocessing
import os
import re
import signal
import sys
import time
import traceback
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

#: the steps a batch can run, in the order they run
STEPS = ("classify", "simplify", "mesh")
#: output file names in a part's folder, per step
OUTPUT_NAMES = {
    "classify": {
        "classify_report": "classify.json",
        "classified": "classified.step",
        "classify_view": "classify.view.json",
        "classify_png": "classify.png",
    },
    "simplify": {
        "simplified": "simplified.step",
        "simplify_report": "simplify.json",
        "simplify_view": "simplify.view.json",
        "simplify_png": "simplify.png",
    },
    "mesh": {"mesh": "mesh.msh", "mesh_report": "mesh.json", "mesh_png": "mesh.png"},
}
LOG_NAME = "batch.log"
#: the temporaries of medax.io_utils (``.NAME.XXXXXXXX.tmpSUFFIX``)
_TEMP = re.compile(r"^\..*\.[0-9a-f]{8}\.tmp(\.[^.]*)?$")
#: seconds to wait for a child that sent its record to exit
_EXIT_WAIT = 30.0
#: modules the fork server imports once, so that forked children start warm
PRELOAD = ["medax.batch.preload"]


@dataclass(frozen=True)
class PartTask:
    """What a worker needs for one part: paths and plain options, nothing else.

    ``options``: ``angle``, ``tol`` (classify), ``simplify_tol``, ``strict_volume``
    (simplify's ``--strict-volume``, present only when set), ``mesh_size`` and ``pictures``
    (bool). ``hook``: ``"module:function"`` called with the part's path in the
    child before the work (tests use it to make a part hang or crash)."""

    path: str
    sha256: str
    options_key: str
    outdir: str
    part_dir: str
    do: tuple[str, ...]
    options: Mapping[str, Any] = field(default_factory=dict)
    timeout: float | None = None
    hook: str | None = None


def run_part(task: PartTask) -> dict[str, Any]:
    """The Dask task: run ``task`` in a child process, kill it after ``task.timeout``
    seconds, and return its record (status ``ok``, ``refused``, ``failed`` or
    ``timeout``)."""
    start = time.perf_counter()
    started = time.time()
    base = base_record(task)
    folder = Path(task.outdir, task.part_dir)
    folder.mkdir(parents=True, exist_ok=True)
    _remove_temporaries(folder)  # left by a run of this part on a worker that was killed
    if multiprocessing.current_process().daemon:  # cannot have multiprocessing children
        rec = _run_in_interpreter(task, base, start, folder)
        return _stamp_worker(rec, start, started)
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(PRELOAD)
    recv, send = ctx.Pipe(duplex=False)
    child = ctx.Process(target=_child, args=(task, send), name=f"medax-part-{task.part_dir}")
    child.start()
    send.close()
    record: dict[str, Any] | None = None
    try:
        if recv.poll(task.timeout):
            with contextlib.suppress(EOFError, OSError):
                record = recv.recv()
        else:
            child.kill()
            child.join()
            _remove_temporaries(folder)
            return _timed_out(base, start, task)
        child.join(_EXIT_WAIT)
        if child.is_alive():
            child.kill()
            child.join()
    finally:
        recv.close()
        if child.is_alive():  # the worker is being stopped while waiting
            child.kill()
            child.join()
    if record is None:
        _remove_temporaries(folder)
        return finish(base, "failed", start, f"the part's process {_exit_text(child.exitcode)}")
    return _stamp_worker(record, start, started)


def _stamp_worker(record: dict[str, Any], start: float, started: float) -> dict[str, Any]:
    if record["status"] != "timeout":
        record["wall_s"] = round(time.perf_counter() - start, 3)
    record["started"] = round(started, 3)
    record["worker"] = _worker_address()
    return record


def _run_in_interpreter(
    task: PartTask, base: dict[str, Any], start: float, folder: Path
) -> dict[str, Any]:
    """The part in a new interpreter (``python -m medax.batch.child``): for a daemonic
    worker, which ``multiprocessing`` forbids to have children. Each part pays medax's and
    OCP's import (about 2.5 s of CPU); the timeout and the kill are the same."""
    import select
    import subprocess

    read_fd, write_fd = os.pipe()
    cmd = [sys.executable, "-m", "medax.batch.child", str(write_fd)]
    try:
        path = os.pathsep.join(p for p in sys.path if p)  # the worker's modules, as a fork
        env = dict(os.environ, PYTHONPATH=path)
        proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, pass_fds=(write_fd,), env=env)
    finally:
        os.close(write_fd)
    data = b""
    try:
        assert proc.stdin is not None
        proc.stdin.write(json.dumps(asdict(task)).encode())
        proc.stdin.close()
        deadline = None if task.timeout is None else time.monotonic() + task.timeout
        while True:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            ready, _, _ = select.select([read_fd], [], [], left)
            if not ready:
                proc.kill()
                proc.wait()
                _remove_temporaries(folder)
                return _timed_out(base, start, task)
            chunk = os.read(read_fd, 1 << 16)
            if not chunk:
                break
            data += chunk
        try:
            proc.wait(_EXIT_WAIT)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    finally:
        os.close(read_fd)
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    try:
        record: dict[str, Any] = json.loads(data)
        return record
    except ValueError:
        _remove_temporaries(folder)
        return finish(base, "failed", start, f"the part's process {_exit_text(proc.returncode)}")


def _worker_address() -> str:
    """The Dask worker's address ('' outside a worker)."""
    try:
        from distributed import get_worker

        return str(get_worker().address)
    except (ImportError, ValueError):
        return ""


def _child(task: PartTask, conn: Connection) -> None:
    """The forked child: its record through ``conn``."""
    record = _child_record(task)
    conn.send(record)
    conn.close()


def child_main(argv: list[str] | None = None) -> int:
    """``python -m medax.batch.child FD``: the task as JSON on stdin, the record as JSON
    on the file descriptor FD."""
    fd = int((argv if argv is not None else sys.argv[1:])[0])
    data = json.loads(sys.stdin.read())
    data["do"] = tuple(data["do"])
    record = _child_record(PartTask(**data))
    with os.fdopen(fd, "wb") as f:
        f.write(json.dumps(record).encode())
    return 0


def _child_record(task: PartTask) -> dict[str, Any]:
    """The child's body: log to the part's folder, run the hook, do the work; the record."""
    _die_with_parent()
    folder = Path(task.outdir, task.part_dir)
    log = os.open(folder / LOG_NAME, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o666)
    sys.stdout.flush()
    sys.stderr.flush()
    os.dup2(log, 1)  # OCCT's own messages too
    os.dup2(log, 2)
    os.close(log)
    start = time.perf_counter()
    try:
        if task.hook:
            module, _, name = task.hook.partition(":")
            getattr(importlib.import_module(module), name)(task.path)
        record = work(task)
    except BaseException as err:  # noqa: B036 - reported, never raised in a child
        traceback.print_exc()
        record = finish(base_record(task), "failed", start, one_line(err))
    record["cpu_s"] = round(time.process_time(), 3)  # this process's, since its fork
    sys.stdout.flush()
    sys.stderr.flush()
    return record


def work(task: PartTask) -> dict[str, Any]:
    """Run ``task.do`` on the part in this process; its record (no ``wall_s``)."""
    from medax.cli.main import build_parser
    from medax.errors import MedaxError

    start = time.perf_counter()
    record = base_record(task)
    folder = Path(task.outdir, task.part_dir)
    status, error = "ok", None
    for step in task.do:
        argv, outputs = step_argv(step, task, record["outputs"])
        print(f"$ medax {' '.join(argv)}", flush=True)
        t0 = time.perf_counter()
        try:
            args = build_parser().parse_args(argv)
            args.run(args)
            step_status = "ok"
        except MedaxError as err:
            step_status, error = "refused", f"{step}: {one_line(err)}"
        except Exception as err:
            traceback.print_exc()
            step_status, error = "failed", f"{step}: {one_line(err)}"
        record["steps"][step] = {
            "status": step_status,
            "time_s": round(time.perf_counter() - t0, 3),
        }
        if step_status != "ok":
            status = step_status
            break
        record["outputs"].update(
            {k: str(Path(task.part_dir, Path(p).name)) for k, p in outputs.items()}
        )
    _read_reports(record, folder)
    return finish(record, status, start, error)


def step_argv(
    step: str, task: PartTask, done: Mapping[str, str]
) -> tuple[list[str], dict[str, str]]:
    """The ``medax`` arguments of ``step`` and the outputs it writes (key -> path); the mesh
    is made on the simplified part when simplify ran."""
    folder = Path(task.outdir, task.part_dir)
    opts = task.options
    names = {k: str(folder / v) for k, v in OUTPUT_NAMES[step].items()}
    pictures = bool(opts.get("pictures"))
    if not pictures:
        names = {k: v for k, v in names.items() if not k.endswith("_png")}
    if step == "classify":
        argv = ["classify", task.path, "--report", names["classify_report"]]
        argv += ["--step", names["classified"], "--view3d", names["classify_view"]]
        argv += ["--angle", repr(opts["angle"]), "--tol", repr(opts["tol"])]
        if pictures:
            argv += ["--png", names["classify_png"]]
    elif step == "simplify":
        argv = ["simplify", task.path, "-o", names["simplified"]]
        argv += ["--report", names["simplify_report"], "--tol", repr(opts["simplify_tol"])]
        argv += ["--view3d", names["simplify_view"]]
        if opts.get("strict_volume"):
            argv.append("--strict-volume")
        if pictures:
            argv += ["--png", names["simplify_png"]]
    elif step == "mesh":
        source = str(folder / Path(done["simplified"]).name) if "simplified" in done else task.path
        argv = ["mesh", source, "--size", repr(opts["mesh_size"]), "-o", names["mesh"]]
        argv += ["--report", names["mesh_report"]]
        if pictures:
            argv += ["--plot", names["mesh_png"]]
    else:
        raise ValueError(f"unknown step '{step}'")
    return argv, names


def _read_reports(record: dict[str, Any], folder: Path) -> None:
    """Counts, unit and kept reasons from the reports the steps wrote."""
    counts = record["counts"]
    outs = record["outputs"]

    def load(key: str) -> dict[str, Any] | None:
        if key not in outs:
            return None
        data: dict[str, Any] = json.loads((folder / Path(outs[key]).name).read_text("utf-8"))
        return data

    classes = load("classify_report")
    if classes is not None:
        s = classes["summary"]
        counts.update(
            faces=s["faces"], fillets=s["fillet"], corner_blends=s["corner_blend"], axes=s["axes"]
        )
        record["units"]["length"] = classes["unit"]
    simple = load("simplify_report")
    if simple is not None:
        counts.update(
            faces_before=simple["faces_before"],
            faces_after=simple["faces_after"],
            blends_found=simple["blends_found"],
            blends_removed=len(simple["blends_removed"]),
            blends_kept=len(simple["blends_kept"]),
        )
        record["kept_reasons"] = dict(simple.get("kept_reasons", {}))
        record["valid"] = bool(simple["valid"])
        record["units"]["length"] = simple["units"]["length"]
    mesh = load("mesh_report")
    if mesh is not None:
        counts["mesh_quads"] = mesh.get("n_quads", 0)
        counts["mesh_structured_faces"] = mesh.get("n_structured_faces", 0)


def base_record(task: PartTask) -> dict[str, Any]:
    """A record of ``task`` with its header and no result yet (status ``failed``)."""
    from medax import __version__
    from medax.schemas import SCHEMA_VERSION

    return {
        "medax_version": __version__,
        "schema_version": SCHEMA_VERSION,
        "kind": "batch-record",
        "units": {"length": "unspecified", "time": "s"},
        "tolerances": tolerances_of(task.options),
        "input": task.path,
        "sha256": task.sha256,
        "options_key": task.options_key,
        "part_dir": task.part_dir,
        "do": list(task.do),
        "status": "failed",
        "steps": {},
        "counts": {},
        "kept_reasons": {},
        "outputs": {},
    }


def tolerances_of(options: Mapping[str, Any]) -> dict[str, float]:
    """The tolerances in ``options``, under the reports' names."""
    names = {"angle": "tangent_angle_rad", "tol": "axis_curve_tol_rel"}
    names["simplify_tol"] = "deviation_tol_rel"
    return {names[k]: float(v) for k, v in options.items() if k in names}


def finish(record: dict[str, Any], status: str, start: float, error: str | None) -> dict[str, Any]:
    """``record`` with its status, the time since ``start`` and the error line, if any."""
    record["status"] = status
    record["time_s"] = round(time.perf_counter() - start, 3)
    if error:
        record["error"] = error
    return record


def _timed_out(base: dict[str, Any], start: float, task: PartTask) -> dict[str, Any]:
    return finish(base, "timeout", start, f"killed after the {task.timeout:g} s timeout")


def one_line(err: BaseException) -> str:
    """``Type: message`` on one line, at most 500 characters."""
    text = " ".join(str(err).split()) or type(err).__name__
    return f"{type(err).__name__}: {text}"[:500]


def _exit_text(code: int | None) -> str:
    if code is not None and code < 0:
        with contextlib.suppress(ValueError):
            return f"was killed by {signal.Signals(-code).name}"
        return f"was killed by signal {-code}"
    return f"exited with code {code} before sending its record"


def _remove_temporaries(folder: Path) -> None:
    """Remove the staged temporaries a killed child left in its folder."""
    for p in folder.iterdir():
        if _TEMP.match(p.name):
            with contextlib.suppress(OSError):
                p.unlink()


def _die_with_parent() -> None:
    """Linux: SIGKILL this process when its parent, the worker's fork server, exits.

    The fork server exits when no process holds its "alive" pipe; it gave this child a copy
    (for processes of its own), which is closed here, so that the server and this process end
    with their Dask worker when the worker is killed."""
    from multiprocessing import forkserver

    server = getattr(forkserver, "_forkserver", None)
    fd = getattr(server, "_forkserver_alive_fd", None)
    if fd is not None:
        with contextlib.suppress(OSError):
            os.close(fd)
        server._forkserver_alive_fd = None  # type: ignore[union-attr]
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    parent = os.getppid()
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(1, int(signal.SIGKILL))  # PR_SET_PDEATHSIG
    if os.getppid() != parent:  # the server exited before the signal was asked for
        os._exit(1)


def as_dict(task: PartTask) -> dict[str, Any]:
    """``task`` as plain data (for logs)."""
    return asdict(task)
