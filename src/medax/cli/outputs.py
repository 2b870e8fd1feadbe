"""Check a subcommand's output paths before any work.

Every output must be writable (see :func:`medax.io_utils.check_writable`), have a suffix its
writer understands, and name a file that is neither an input nor another output (compared
as the same file, so through symbolic and hard links too). The first problem found is raised
as a one-line :class:`~medax.errors.InputError`.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

from medax.errors import InputError
from medax.io_utils import check_writable

JSON_SUFFIXES = (".json",)
PLOT_SUFFIXES = (".png", ".svg", ".pdf")


class Output:
    """One output option: its flag, the path given (None: not asked for) and the suffixes
    its writer accepts (None: any, the format is checked elsewhere)."""

    def __init__(self, option: str, path: str | None, suffixes: Sequence[str] | None) -> None:
        self.option = option
        self.path = path
        self.suffixes = None if suffixes is None else tuple(suffixes)


def check_outputs(outputs: Sequence[Output], inputs: Mapping[str, str]) -> None:
    """Refuse (InputError) any output that cannot or must not be written; ``inputs`` maps
    a label (e.g. ``"input part"``) to each input path."""
    asked = [o for o in outputs if o.path is not None]
    for o in asked:
        assert o.path is not None
        check_writable(o.path, o.option)
        _check_suffix(o)
    for o in asked:
        assert o.path is not None
        for label, src in inputs.items():
            if same_file(o.path, src):
                raise InputError(f"{o.option} '{o.path}': is the {label}; choose another name")
    for i, a in enumerate(asked):
        for b in asked[i + 1 :]:
            assert a.path is not None and b.path is not None
            if same_file(a.path, b.path):
                raise InputError(
                    f"{a.option} '{a.path}' and {b.option} '{b.path}' name the same file"
                )


def same_file(a: str | Path, b: str | Path) -> bool:
    """Whether two paths name one file: ``os.path.samefile`` when both exist (hard links,
    symbolic links), else the same resolved path."""
    try:
        if os.path.exists(a) and os.path.exists(b):
            return os.path.samefile(a, b)
    except OSError:
        pass
    return os.path.realpath(a) == os.path.realpath(b)


def _check_suffix(o: Output) -> None:
    if o.suffixes is None:
        return
    assert o.path is not None
    suffix = Path(o.path).suffix.lower()
    if suffix not in o.suffixes:
        got = f"'{suffix}'" if suffix else "no extension"
        raise InputError(
            f"{o.option} '{o.path}': {got} is not a known extension here "
            f"(use {', '.join(o.suffixes)})"
        )
