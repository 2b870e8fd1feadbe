"""numpy core (+ meshio for files): structured quad meshes from medial axes (paper, section 4)."""

from medax.mesh.export import FORMATS, format_from_path, write_mesh
from medax.mesh.grid import QuadMesh, structured_quads
from medax.mesh.mesher import METHODS, divisions_for_size, mesh_region
from medax.mesh.quality import QuadQuality, quad_quality, summarize

__all__ = [
    "FORMATS",
    "METHODS",
    "QuadMesh",
    "QuadQuality",
    "divisions_for_size",
    "format_from_path",
    "mesh_region",
    "quad_quality",
    "structured_quads",
    "summarize",
    "write_mesh",
]
