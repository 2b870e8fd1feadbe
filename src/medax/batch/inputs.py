"""The parts of a batch: files, folders (searched recursively) and glob patterns."""

from __future__ import annotations

import glob
import hashlib
import os
from collections.abc import Iterable, Sequence
from pathlib import Path

from medax.errors import InputError

#: the CAD files a folder or a glob contributes (an explicitly named file may be anything)
PART_SUFFIXES = (".step", ".stp", ".brep")


def collect_inputs(items: Sequence[str], exclude: str | Path | None = None) -> list[Path]:
    """The part files named by ``items``, in order, each once (by real path).

    A file is taken as given; a folder contributes its ``.step``/``.stp``/``.brep`` files,
    recursively and sorted; anything else is a glob pattern (``**`` allowed). Files under
    ``exclude`` (the batch's output folder) are skipped when found in a folder or a glob.
    :class:`InputError` for an item that names nothing, and when no part is found."""
    skip = Path(os.path.realpath(exclude)) if exclude is not None else None
    found: list[Path] = []
    seen: set[str] = set()

    def add(paths: Iterable[Path], explicit: bool) -> None:
        for p in paths:
            real = os.path.realpath(p)
            if not explicit and skip is not None and Path(real).is_relative_to(skip):
                continue
            if real not in seen:
                seen.add(real)
                found.append(p)

    for item in items:
        path = Path(item)
        if path.is_file():
            add([path], explicit=True)
        elif path.is_dir():
            add(sorted(p for p in path.rglob("*") if _is_part(p)), explicit=False)
        elif glob.has_magic(item):
            matches = sorted(Path(m) for m in glob.glob(item, recursive=True))
            parts = [p for p in matches if _is_part(p)]
            if not parts:
                raise InputError(f"'{item}': the pattern matches no .step, .stp or .brep file")
            add(parts, explicit=False)
        else:
            raise InputError(f"'{item}': no such file or folder")
    if not found:
        raise InputError("no part found (folders are searched for .step, .stp and .brep files)")
    return found


def _is_part(p: Path) -> bool:
    return p.suffix.lower() in PART_SUFFIXES and p.is_file() and not p.name.startswith(".")


def file_sha256(path: str | Path) -> str:
    """The SHA-256 of a file's bytes, as hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def part_dirs(paths: Sequence[Path], hashes: Sequence[str]) -> list[str]:
    """A folder name per part: its stem, or ``stem-<8 hex of its hash>`` when several parts
    share the stem (``a/bracket.step`` and ``b/bracket.stp``), then ``-2``, ``-3``... for
    copies with the same bytes."""
    stems = [p.stem for p in paths]
    names = [
        s if stems.count(s) == 1 else f"{s}-{h[:8]}" for s, h in zip(stems, hashes, strict=True)
    ]
    out: list[str] = []
    for name in names:
        k, unique = 1, name
        while unique in out:
            k += 1
            unique = f"{name}-{k}"
        out.append(unique)
    return out
