"""Demo part: the paper's two mesh figures (Fig. 14 and Fig. 17) on the sample regions."""

from __future__ import annotations

from pathlib import Path

from medax.geometry.region_io import read_regions, sample_regions_path
from medax.mesh.export import write_mesh
from medax.mesh.mesher import mesh_region

#: (file stem, region, divisions, method, title)
DEMO_MESHES = (
    ("mesh-fig14-arcs-4x4", "arcs", (4, 4), "paper",
     "Fig. 14: 4x4 quads from 3 + 3 recursive medial axes (paper method)"),
    ("mesh-fig17-wavy-16x17", "wavy", (16, 17), "ratio",
     "Fig. 17: wavy region, 31 axes (15 + 16 constant-ratio curves), 16x17 quads"),
)  # fmt: skip


def demo(outdir: Path) -> list[Path]:
    """Mesh, write ``<stem>.vtu`` and ``<stem>.png`` into ``outdir``."""
    from medax.io_utils import atomic_path
    from medax.viz.mesh_plot import plot_mesh

    regions = read_regions(sample_regions_path())
    written: list[Path] = []
    for stem, name, div, method, title in DEMO_MESHES:
        # Fig. 17's lines are the curves of constant ratio: boundary nodes at their ends
        mesh = mesh_region(regions[name], divisions=div, method=method, tol=1e-7, boundary="ratio")
        q = mesh.quality()
        written.append(write_mesh(outdir / f"{stem}.vtu", mesh.points, mesh.quads, q.as_dict()))
        png = outdir / f"{stem}.png"
        with atomic_path(png) as tmp:
            plot_mesh(mesh, tmp, title=title)
        written.append(png)
    return written
