"""Memory and time estimates of a mesh run from its node count, said before the work, and
the limit above which a run is refused unless ``--force``.

The costs are fits of ``medax mesh`` runs (peak resident memory and wall time of the whole
command, writing a .vtu) on this package's sample regions and parts; see CHANGELOG.md.
"""

from __future__ import annotations

import logging
import math
import os
from dataclasses import dataclass
from pathlib import Path

from medax.errors import InputError

log = logging.getLogger(__name__)

GB = 1e9
#: region meshes (ratio and angle methods), .vtu or .msh: peak memory of the command
#: (bytes) = base + per node (wavy, 128^2 - 2048^2: 95 MB - 2.43 GB) ...
REGION_BASE_BYTES = 100e6
REGION_BYTES_PER_NODE = 600.0
#: ... and wall time (s) = base + per node (0.55 s of the 7.5 s at 1024^2 are the mesher's,
#: the rest quality, checks and writing; 178 s at 4096^2)
REGION_BASE_S = 1.0
REGION_S_PER_NODE = 10e-6
#: a --plot adds this per node (wavy 1024^2: 0.70 -> 1.12 GB, 7.5 -> 21 s)
PLOT_BYTES_PER_NODE = 400.0
PLOT_S_PER_NODE = 13e-6
#: the paper's recursion (trapezoid, 32^2 and 64^2; free-form sides take far longer:
#: wavy about 40 s at 16^2)
PAPER_BYTES_PER_NODE = 33e3
PAPER_S_PER_NODE = 2.1e-3
#: part meshes (``mesh PART --size H``, nodes estimated as surface area / H^2, 1.1 - 1.2
#: times fewer than written; l-bracket, H 2 - 0.125: 350 MB - 0.71 GB, 2.9 - 77 s; the time
#: grows faster than the node count, the per-node time is that of the largest run)
PART_BASE_BYTES = 350e6
PART_BYTES_PER_NODE = 1300.0
PART_BASE_S = 3.0
PART_S_PER_NODE = 260e-6
#: estimates above either are printed on stderr before the work
NOTE_BYTES = 1 * GB
NOTE_S = 10.0
#: a run is refused above this share of the available memory ...
MEMORY_SHARE = 0.5
#: ... or above this fixed cap (bytes), whichever is lower
MAX_BYTES = 8 * GB


@dataclass(frozen=True)
class Estimate:
    """Estimated cost of a run: ``nodes`` mesh nodes, ``bytes`` peak memory, ``seconds``."""

    nodes: int
    bytes: float
    seconds: float

    def text(self) -> str:
        """``"1.05e+06 nodes, about 0.75 GB and 8 s"``."""
        return f"{self.nodes:.3g} nodes, about {_gb(self.bytes)} and {_duration(self.seconds)}"


def region_estimate(n1: int, n2: int, method: str = "ratio", plot: bool = False) -> Estimate:
    """Estimate of ``medax mesh`` on a region with ``n1 x n2`` quads ((n1+1)(n2+1) nodes)
    by ``method``, with a ``--plot`` or not."""
    nodes = (n1 + 1) * (n2 + 1)
    per_byte, per_s = REGION_BYTES_PER_NODE, REGION_S_PER_NODE
    if method == "paper":
        per_byte, per_s = PAPER_BYTES_PER_NODE, PAPER_S_PER_NODE
    if plot:
        per_byte, per_s = per_byte + PLOT_BYTES_PER_NODE, per_s + PLOT_S_PER_NODE
    return Estimate(nodes, REGION_BASE_BYTES + per_byte * nodes, REGION_BASE_S + per_s * nodes)


def part_estimate(area: float, size: float) -> Estimate:
    """Estimate of ``medax mesh PART --size size`` on a part of surface ``area`` (model
    units^2): about one node per ``size^2``."""
    nodes = math.ceil(min(area / size**2, 1e18))
    return Estimate(
        nodes, PART_BASE_BYTES + PART_BYTES_PER_NODE * nodes, PART_BASE_S + PART_S_PER_NODE * nodes
    )


def available_memory() -> float | None:
    """Memory available to a new run (bytes): MemAvailable of /proc/meminfo, else the
    physical memory (os.sysconf), else None."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return float(line.split()[1]) * 1024.0  # kB
    except (OSError, ValueError, IndexError):
        pass
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return None


def memory_limit() -> tuple[float, str]:
    """The memory limit of a run (bytes) and where it comes from (for the message)."""
    avail = available_memory()
    if avail is not None and MEMORY_SHARE * avail < MAX_BYTES:
        return MEMORY_SHARE * avail, f"{MEMORY_SHARE:g} of the {_gb(avail)} of memory available"
    return MAX_BYTES, "the fixed cap"


def check_estimate(est: Estimate, what: str, force: bool, command: str = "mesh") -> None:
    """Print ``est`` on stderr when it is large; InputError naming it, the limit and
    ``--force`` when its memory exceeds :func:`memory_limit` and ``force`` is not set.
    ``what`` names the run (e.g. ``"--divisions 4096,4096"``)."""
    limit, source = memory_limit()
    if est.bytes > limit and not force:
        raise InputError(
            f"{what}: {est.text()}, above the limit {_gb(limit)} ({source}); --force runs it anyway"
        )
    if est.bytes > NOTE_BYTES or est.seconds > NOTE_S or est.bytes > limit:
        log.info("%s: %s: estimated %s", command, what, est.text())


def _gb(n: float) -> str:
    return f"{n / GB:.3g} GB"


def _duration(s: float) -> str:
    if s < 10.0:
        return f"{s:.2g} s"
    if s < 120.0:
        return f"{s:.0f} s"
    if s < 7200.0:
        return f"{s / 60:.3g} min"
    return f"{s / 3600:.3g} h"
