"""A gmsh session: initialised quietly for a block of work, finalised after it."""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from typing import Any


@contextlib.contextmanager
def gmsh_session() -> Iterator[Any]:
    """The ``gmsh`` module, initialised (no config files, no signal handlers, no terminal
    output) for the duration and finalised after, unless it was already running. gmsh's
    initialisation resets SIGTERM to the default action; the handler set before (the
    command line's: a clean stop, no output, temporaries removed) is put back."""
    import gmsh  # noqa: PLC0415

    mine = not gmsh.isInitialized()
    if mine:
        main = threading.current_thread() is threading.main_thread()
        term = signal.getsignal(signal.SIGTERM) if main else None
        gmsh.initialize(readConfigFiles=False, interruptible=False)
        if term is not None:
            signal.signal(signal.SIGTERM, term)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        yield gmsh
    finally:
        if mine:
            gmsh.finalize()
