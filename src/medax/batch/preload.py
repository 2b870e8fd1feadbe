"""Imported once by each worker's fork server, so that every part's process starts with
medax, its subcommands and OCP loaded (this module imports OCP only through them)."""

from __future__ import annotations

import medax.cad.classify  # noqa: F401
import medax.cad.reader  # noqa: F401
import medax.cad.simplify  # noqa: F401
import medax.cli.classify  # noqa: F401
import medax.cli.main  # noqa: F401
import medax.cli.simplify  # noqa: F401
