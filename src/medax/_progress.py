"""Progress with counts through :mod:`logging` (INFO), at a granularity that does not flood.

The library never prints; the ``medax`` command shows these messages with ``-v``.
"""

from __future__ import annotations

import logging


def log_progress(log: logging.Logger, what: str, done: int, total: int, steps: int = 10) -> None:
    """Log ``"<what> <done>/<total>"`` at INFO for about ``steps`` evenly spaced values of
    ``done`` (1-based) and for the last one."""
    if total > 0 and (done == total or done % max(1, total // steps) == 0):
        log.info("%s %d/%d", what, done, total)
