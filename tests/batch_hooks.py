"""Hooks the batch tests pass as ``BatchOptions.hook``: called with the part's path in the
part's process before the work (never reachable from the command line)."""

import os
import time
from pathlib import Path


def hang_if_named(path: str) -> None:
    """A part whose name starts with ``hang`` hangs (its pid in ``<path>.pid``)."""
    if Path(path).name.startswith("hang"):
        Path(path + ".pid").write_text(str(os.getpid()))
        time.sleep(3600)


def slow_once(path: str) -> None:
    """A part whose name starts with ``slow`` sleeps the first time it runs, after writing
    its pid to ``<path>.started``; the next time it runs at once."""
    marker = Path(path + ".started")
    if Path(path).name.startswith("slow") and not marker.exists():
        marker.write_text(str(os.getpid()))
        time.sleep(3600)


def kill_worker(path: str) -> None:
    """A part whose name starts with ``crash`` kills its Dask worker (the parent of this
    process's parent when that is a fork server, else this process's parent) every time it
    runs."""
    if Path(path).name.startswith("crash"):
        worker = os.getppid()
        if b"forkserver" in Path(f"/proc/{worker}/cmdline").read_bytes():
            stat = Path(f"/proc/{worker}/stat").read_text()
            worker = int(stat.rsplit(")", 1)[1].split()[1])
        os.kill(worker, 9)
        time.sleep(60)
