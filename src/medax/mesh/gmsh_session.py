"""A gmsh session: initialised quietly for a block of work, finalised after it."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any


@contextlib.contextmanager
def gmsh_session() -> Iterator[Any]:
    """The ``gmsh`` module, initialised (no config files, no signal handlers, no terminal
    output) for the duration and finalised after, unless it was already running."""
    import gmsh  # noqa: PLC0415

    mine = not gmsh.isInitialized()
    if mine:
        gmsh.initialize(readConfigFiles=False, interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        yield gmsh
    finally:
        if mine:
            gmsh.finalize()
