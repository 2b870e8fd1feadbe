"""Entry point of the ``medax`` command.

Each subcommand lives in ``medax.cli.<name>`` and provides ``add_parser(subparsers)`` (which
registers its options) and ``run(args) -> int``. ``main(argv)`` is callable in-process.
``-q`` / ``-v`` are accepted before and after the subcommand's name (see
:func:`configure_logging`). Errors of the :class:`~medax.errors.MedaxError` family and OS
errors are printed on one line with exit code 1; an interrupt (Ctrl-C, or SIGTERM for the
real command) prints one line and exits 130 (143) after every output's temporary file is
removed (outputs are all written at the end, or none).
"""

from __future__ import annotations

import argparse
import gc
import importlib
import logging
import signal
import sys
import threading
from collections.abc import Iterator, Sequence
from contextlib import contextmanager

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
    add_verbosity(parser, before=True)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMANDS:
        try:
            module = importlib.import_module(f"medax.cli.{name}")
        except ModuleNotFoundError as err:
            if err.name == f"medax.cli.{name}":
                continue  # subcommand not built yet
            raise
        module.add_parser(sub)
    for p in {id(p): p for p in sub.choices.values()}.values():  # every subcommand, aliases once
        add_verbosity(p)
    return parser


def add_verbosity(parser: argparse.ArgumentParser, before: bool = False) -> None:
    """``-q/--quiet`` and ``-v/--verbose`` (repeatable) on ``parser``. The main parser counts
    them in ``args.quiet_before`` / ``args.verbose_before`` (``before``), every subparser in
    ``args.quiet`` / ``args.verbose``: a subparser's defaults would otherwise overwrite the
    flags given before the subcommand's name. :func:`main` adds the two."""
    group = parser.add_argument_group("output")
    suffix = "_before" if before else ""
    group.add_argument(
        "-q", "--quiet", action="count", default=0, dest=f"quiet{suffix}",
        help="only warnings and errors",
    )  # fmt: skip
    group.add_argument(
        "-v", "--verbose", action="count", default=0, dest=f"verbose{suffix}",
        help="also progress with counts (fillets, faces, samples); -vv: debug messages",
    )  # fmt: skip


class _Prefix(logging.Formatter):
    """``medax simplify: msg`` for a command's own messages (logged as ``simplify: msg`` by
    ``medax.cli``), ``medax: msg`` for the library's."""

    def format(self, record: logging.LogRecord) -> str:
        sep = " " if record.name.startswith("medax.cli") else ": "
        return f"medax{sep}{record.getMessage()}"


@contextmanager
def configure_logging(verbose: int = 0, quiet: int = 0) -> Iterator[None]:
    """Route the ``medax`` loggers to stderr for one command; restore them afterwards.

    Levels (``verbose - quiet``): below 0 (``-q``) warnings only; 0 the command's stage
    messages (the ``medax.cli`` loggers at INFO, and the first run's "compiling numeric
    kernels" of ``medax.geometry.kernels``: seconds without output otherwise); 1 (``-v``)
    also the library's progress with counts (``medax`` at INFO); 2 (``-vv``) debug messages.
    The handler writes to the current ``sys.stderr`` and is removed on exit, so in-process
    calls (tests, notebooks) neither accumulate handlers nor leave levels changed. A command
    run inside another (``medax demo`` calls :func:`main`) keeps the outer command's handler
    and levels.
    """
    lib, cli = logging.getLogger("medax"), logging.getLogger("medax.cli")
    kern = logging.getLogger("medax.geometry.kernels")
    if any(isinstance(h.formatter, _Prefix) for h in lib.handlers):
        yield
        return
    level = verbose - quiet
    lib_level = logging.DEBUG if level >= 2 else logging.INFO if level == 1 else logging.WARNING
    cli_level = logging.WARNING if level < 0 else min(lib_level, logging.INFO)
    saved = (lib.level, cli.level, kern.level)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(_Prefix())
    lib.addHandler(handler)
    lib.setLevel(lib_level)
    cli.setLevel(cli_level)
    kern.setLevel(cli_level)
    try:
        yield
    finally:
        lib.removeHandler(handler)
        lib.setLevel(saved[0])
        cli.setLevel(saved[1])
        kern.setLevel(saved[2])


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``medax`` with ``argv`` (default ``sys.argv[1:]``); returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    if argv is None:  # the real command, not an in-process call
        _terminate_as_interrupt()
    verbose = args.verbose_before + getattr(args, "verbose", 0)
    with configure_logging(verbose, args.quiet_before + getattr(args, "quiet", 0)):
        code = _run(args)
    if argv is None:
        # the process ends next: its objects need no last garbage collection (numba's
        # typing tables alone made the interpreter's final pass 0.14 s of CPU)
        gc.freeze()
    return code


def _run(args: argparse.Namespace) -> int:
    """``args.run(args)``, with errors and interrupts turned into one line and an exit code."""
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
