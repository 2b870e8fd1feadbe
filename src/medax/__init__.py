"""medax: product-oriented medial axes of CAD models.

The numpy core (``medax.geometry``, ``medax.axis``, ``medax.mesh``) never imports
OpenCASCADE; ``medax.cad`` is the only adapter to it.

Facade, imported on first use: [trace_axis][medax.trace_axis] and
[mesh_region][medax.mesh_region] (numpy core); [read_part][medax.read_part],
[classify][medax.classify], [simplify][medax.simplify], [write_step][medax.write_step] and
[mesh_part][medax.mesh_part] (OCP).
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

from medax.errors import MedaxError

__version__ = "0.1.0"

#: facade name -> module holding it, imported on first access (PEP 562), so that
#: ``import medax`` and the numpy core stay free of OCP and gmsh
_LAZY = {
    "trace_axis": "medax.axis.medial",
    "mesh_region": "medax.mesh.mesher",
    "read_part": "medax.cad.reader",
    "classify": "medax.cad.facade",
    "simplify": "medax.cad.facade",
    "write_step": "medax.cad.simplify.step_out",
    "mesh_part": "medax.cad.part_mesh",
}

__all__ = [
    "MedaxError",
    "__version__",
    "classify",
    "mesh_part",
    "mesh_region",
    "read_part",
    "simplify",
    "trace_axis",
    "write_step",
]

if TYPE_CHECKING:
    from medax.axis.medial import trace_axis
    from medax.cad.facade import classify, simplify
    from medax.cad.part_mesh import mesh_part
    from medax.cad.reader import read_part
    from medax.cad.simplify.step_out import write_step
    from medax.mesh.mesher import mesh_region


def __getattr__(name: str) -> Any:
    """Import a facade function (``medax.trace_axis``, ``medax.simplify``, ...) on first use."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'medax' has no attribute '{name}'")
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])
