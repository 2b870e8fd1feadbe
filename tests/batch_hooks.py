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
