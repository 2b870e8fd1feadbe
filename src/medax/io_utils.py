"""Atomic output files, the one writer every output goes through.

A file is written to a temporary file beside its target (a short hidden name, so a long
target name never pushes it past NAME_MAX), created with mode ``0o666`` less the umask, then
renamed onto the target. On any error or interrupt the temporary is removed and the target
is left as it was. Only regular files are replaced: a target that exists and is anything else
(a character or block device such as ``/dev/null``, a FIFO, a socket) is refused, never
renamed over or written through. A symbolic link is followed: the file it names is replaced
and the link kept.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import secrets
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from medax.errors import InputError, OutputError

#: characters of the target's name and suffix kept in the temporary's name
_NAME_KEEP = 24
_SUFFIX_KEEP = 12


def check_writable(path: str | os.PathLike[str], option: str = "output") -> Path:
    """The real path ``path`` will be written at; :class:`InputError` (before any work) when
    it is empty, names a folder, a missing or unwritable folder, a read-only file or an
    existing file that is not a regular file."""
    text = os.fspath(path)
    where = f"{option} '{text}'"
    if not text:
        raise InputError(f"{option}: empty file name")
    if text.endswith(("/", os.sep)) or Path(text).name in ("", ".", ".."):
        raise InputError(f"{where}: names a folder, not a file")
    real = Path(os.path.realpath(text))
    try:
        st = os.stat(real)
    except FileNotFoundError:
        st = None
    except OSError as err:
        raise InputError(f"{where}: cannot be used ({err.strerror})") from None
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise InputError(f"{where}: is a folder, not a file")
        if not stat.S_ISREG(st.st_mode):
            kind = file_kind(st.st_mode)
            raise InputError(f"{where}: is {kind}, not a regular file; medax does not replace it")
        if not os.access(real, os.W_OK):
            raise InputError(f"{where}: is read-only; not replaced")
    if not real.parent.is_dir():
        raise InputError(f"{where}: folder {Path(text).parent} does not exist")
    if not os.access(real.parent, os.W_OK | os.X_OK):
        raise InputError(f"{where}: folder {Path(text).parent} is not writable")
    return real


def file_kind(mode: int) -> str:
    """'a character device', 'a FIFO', ... for an ``st_mode``."""
    for test, name in (
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISSOCK, "a socket"),
        (stat.S_ISDIR, "a folder"),
    ):
        if test(mode):
            return name
    return "a special file"


class StagedOutputs:
    """Temporaries for several outputs, renamed onto their targets only once all of them are
    written (see :func:`staged_outputs`)."""

    def __init__(self) -> None:
        self._staged: list[tuple[Path, Path, str]] = []

    def path(self, target: str | os.PathLike[str], option: str = "output") -> Path:
        """A fresh temporary beside ``target`` to write instead of it."""
        real = check_writable(target, option)
        tmp = _new_temp(real, option)
        self._staged.append((tmp, real, option))
        return tmp

    def commit(self) -> None:
        """Rename every temporary onto its target (regular files only)."""
        for tmp, real, option in self._staged:
            if not tmp.is_file():
                raise OutputError(f"{option} '{real}': the writer produced no file")
            try:
                st = os.lstat(real)
            except FileNotFoundError:
                st = None
            if st is not None and not stat.S_ISREG(st.st_mode):
                kind = file_kind(st.st_mode)
                raise OutputError(f"{option} '{real}': became {kind} meanwhile; not replaced")
            try:
                os.replace(tmp, real)
            except OSError as err:
                raise OutputError(f"{option} '{real}': cannot write ({err.strerror})") from None

    def discard(self) -> None:
        """Remove the temporaries still there (after an error or an interrupt)."""
        for tmp, _, _ in self._staged:
            with contextlib.suppress(FileNotFoundError):
                tmp.unlink()


@contextlib.contextmanager
def staged_outputs() -> Iterator[StagedOutputs]:
    """All-or-nothing outputs: ``with staged_outputs() as out: write(out.path(target))``.
    On success every target is replaced; on any error (or KeyboardInterrupt) none is."""
    out = StagedOutputs()
    try:
        yield out
        out.commit()
    except OSError as err:
        raise OutputError(f"cannot write ({err.strerror or err})") from None
    finally:
        out.discard()


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], option: str = "output") -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it onto ``path``, on error
    remove it, so no half-written file is ever left behind."""
    with staged_outputs() as out:
        yield out.path(path, option)


def _new_temp(real: Path, option: str) -> Path:
    """Create (O_EXCL, mode 0o666 & ~umask) a short hidden file beside ``real``."""
    suffix = real.suffix[:_SUFFIX_KEEP] if real.suffix.isascii() else ""
    stem = real.name[:_NAME_KEEP]
    for _ in range(8):
        tmp = real.parent / f".{stem}.{secrets.token_hex(4)}.tmp{suffix}"
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        except OSError as err:
            raise OutputError(f"{option} '{real}': cannot write ({err.strerror})") from None
        os.close(fd)
        return tmp
    raise OutputError(f"{option} '{real}': cannot create a temporary file beside it")


def write_json(path: str | os.PathLike[str], data: Any, option: str = "output") -> Path:
    """Write ``data`` as indented JSON, atomically; :class:`OutputError` (nothing written)
    when it holds a NaN or an infinity, which JSON cannot."""
    text = json_text(data, f"{option} '{os.fspath(path)}'")
    with atomic_path(path, option) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def json_text(data: Any, where: str = "JSON") -> str:
    """Indented strict JSON of ``data``; :class:`OutputError` naming the first non-finite
    number's place."""
    try:
        return json.dumps(data, indent=1, allow_nan=False) + "\n"
    except ValueError:
        place = nonfinite_place(data) or "a value"
        raise OutputError(
            f"{where}: not written: {place} is not a finite number (JSON cannot hold NaN or inf)"
        ) from None


def nonfinite_place(data: Any, place: str = "") -> str | None:
    """Where in nested dicts / lists the first NaN or infinity is (``points[3][1]``)."""
    stack: list[tuple[Any, str]] = [(data, place)]
    while stack:
        item, at = stack.pop()
        if isinstance(item, float) and not math.isfinite(item):
            return at or "the value"
        if isinstance(item, dict):
            stack.extend((v, f"{at}.{k}" if at else str(k)) for k, v in reversed(item.items()))
        elif isinstance(item, list | tuple):
            stack.extend((v, f"{at}[{i}]") for i, v in reversed(list(enumerate(item))))
    return None
