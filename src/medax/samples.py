"""The sample files shipped inside the package (``medax/data``), by name.

``medax samples`` lists them and copies them out; :func:`sample_path` gives the packaged
file to read in place. The STEP parts are the catalogue's (:mod:`medax.cad.parts`,
:mod:`medax.cad.simplify.parts`) written once with OCCT 8, so no OCCT is needed to get them.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Sequence
from importlib import resources
from pathlib import Path

from medax.errors import InputError
from medax.io_utils import staged_outputs

#: name -> what it is and what to try on it
SAMPLES = {
    "regions.json": "4-sided regions (trapezoid, arcs, wavy, annulus_sector; mm): "
    "medax axis, medax mesh",
    "box-12-edges.step": "40 x 30 x 20 box, all 12 edges filleted r 4 (26 faces): "
    "medax simplify, medax mesh --simplify",
    "filleted-boss.step": "60 x 40 x 6 plate, boss with a hole, root and top filleted r 2 "
    "(11 faces): medax classify, medax simplify",
    "l-bracket.step": "L-bracket with a hole, two corners filleted r 3 (11 faces): "
    "medax mesh, medax classify",
}


def sample_names() -> list[str]:
    """Names of the packaged samples, in listing order."""
    return list(SAMPLES)


def sample_path(name: str) -> Path:
    """The packaged file ``name``; :class:`InputError` naming the known ones otherwise."""
    if name not in SAMPLES:
        raise InputError(f"no sample named '{name}' (samples: {', '.join(SAMPLES)})")
    path = Path(str(resources.files("medax") / "data" / name))
    if not path.is_file():  # pragma: no cover - a broken installation
        raise InputError(f"sample '{name}': {path} is missing from the installed package")
    return path


def copy_samples(names: Sequence[str], folder: str | os.PathLike[str]) -> list[Path]:
    """Copy the samples ``names`` into ``folder`` (created if missing); returns the paths.

    Nothing is copied when any name is unknown or any target exists (an existing file is
    never overwritten), and the copies appear together or not at all."""
    dest = Path(folder)
    paths = [sample_path(n) for n in dict.fromkeys(names)]
    if not paths:
        raise InputError("name at least one sample to copy")
    if dest.exists() and not dest.is_dir():
        raise InputError(f"{dest}: exists and is not a folder")
    targets = [dest / p.name for p in paths]
    existing = [str(t) for t in targets if t.exists() or t.is_symlink()]
    if existing:
        raise InputError(
            f"{', '.join(existing)}: already there; nothing copied (never overwritten)"
        )
    try:
        dest.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputError(f"{dest}: cannot create the folder ({err.strerror})") from None
    with staged_outputs() as out:
        for src, target in zip(paths, targets, strict=True):
            shutil.copyfile(src, out.path(target, str(target)))
    return targets
