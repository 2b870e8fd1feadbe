"""Demo part: medial axes of the embedded sample regions."""

from __future__ import annotations

from pathlib import Path

from medax.axis import trace_axis
from medax.cli.axis import axis_document
from medax.geometry.region_io import (
    length_unit,
    load_region_file,
    read_regions,
    sample_regions_path,
)
from medax.io_utils import atomic_path, write_json

#: (region, pairs) traced by the demo: the paper's wavy region both ways and the bent channel
DEMO_REGIONS = (("wavy", ((0, 2), (1, 3))), ("annulus_sector", ((0, 2), (1, 3))))


def demo(outdir: Path) -> list[Path]:
    """Trace, write ``axis-<region>.json`` and ``axis-<region>.png`` into ``outdir``."""
    from medax.viz.axis_plot import plot_axes

    regions = read_regions(sample_regions_path())
    unit = length_unit(load_region_file(sample_regions_path()))
    written: list[Path] = []
    for name, pairs in DEMO_REGIONS:
        region = regions[name]
        axes = [trace_axis(region, pr) for pr in pairs]
        written.append(write_json(outdir / f"axis-{name}.json", axis_document(axes, unit)))
        png = outdir / f"axis-{name}.png"
        with atomic_path(png) as tmp:
            plot_axes(region, axes, tmp)
        written.append(png)
    return written
