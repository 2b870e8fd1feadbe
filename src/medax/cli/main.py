"""Entry point of the ``medax`` command.

Each subcommand lives in ``medax.cli.<name>`` and provides ``add_parser(subparsers)`` (which
registers its options) and ``run(args) -> int``. ``main(argv)`` is callable in-process.
Errors of the :class:`~medax.errors.MedaxError` family and OS errors are printed on one
line with exit code 1; an interrupt (Ctrl-C, or SIGTERM for the real command) prints one
line and exits 130 (143) after every output's temporary file is removed (outputs are all
written at the end, or none).
"""

from __future__ import annotations

import argparse
import importlib
import logging
import signal
import sys
import threading
from collections.abc import Sequence

from medax import __version__
from medax.errors import MedaxError

SUBCOMMANDS = ("axis", "mesh", "classify", "simplify", "batch", "samples", "demo")


def versions() -> str:
    """One line: medax's version and those of the libraries whose results it depends on."""
    from importlib.metadata import PackageNotFoundError, version

    import numpy

    from medax.cad.versions import occt_version

    parts = [f"medax {__version__}", occt_version(), f"numpy {numpy.__version__}"]
    try:
        parts.append(f"gmsh {version('gmsh')}")
    except PackageNotFoundError:
        parts.append("gmsh: not installed")
    return ", ".join(parts)


class _Version(argparse.Action):
    """``--version``: imports the libraries only when asked."""

    def __call__(self, parser, namespace, values, option_string=None):  # type: ignore[no-untyped-def]
        print(versions())
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every available subcommand registered."""
    parser = argparse.ArgumentParser(
        prog="medax",
        description="Product-oriented medial axes of 4-sided regions and CAD faces, fillet "
        "simplification of STEP solids, and structured quad meshes.",
    )
    parser.add_argument(
        "--version",
        action=_Version,
        nargs=0,
        help="print medax's version and those of OpenCASCADE, OCP, numpy and gmsh, and exit",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress to stderr")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMANDS:
        try:
            module = importlib.import_module(f"medax.cli.{name}")
        except ModuleNotFoundError as err:
            if err.name == f"medax.cli.{name}":
                continue  # subcommand not built yet
            raise
        module.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``medax`` with ``argv`` (default ``sys.argv[1:]``); returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="medax: %(message)s",
        stream=sys.stderr,
    )
    if argv is None:  # the real command, not an in-process call
        _terminate_as_interrupt()
    try:
        return int(args.run(args))
    except MedaxError as err:
        print(f"medax {args.command}: error: {err}", file=sys.stderr)
        return 1
    except OSError as err:  # a file system failure not caught nearer (disk full, EIO)
        where = f"{err.filename}: " if err.filename else ""
        print(f"medax {args.command}: error: {where}{err.strerror or err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as err:
        what = "terminated" if isinstance(err, Terminated) else "interrupted"
        print(f"medax {args.command}: {what}; no output written", file=sys.stderr)
        return 143 if isinstance(err, Terminated) else 130


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that the outputs' temporaries are removed."""


def _terminate_as_interrupt() -> None:
    def handler(signum: int, frame: object) -> None:
        raise Terminated()

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, handler)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
