"""medax: product-oriented medial axes of CAD models.

The numpy core (``medax.geometry``, ``medax.axis``, ``medax.mesh``) never imports
OpenCASCADE; ``medax.cad`` is the only adapter to it.
"""

from medax.errors import MedaxError

__all__ = ["MedaxError", "__version__"]
__version__ = "0.1.0"
