"""The OpenCASCADE and OCP versions medax runs on (for ``medax --version``)."""

from __future__ import annotations


def occt_version() -> str:
    """'OpenCASCADE X.Y.Z (OCP V)': OCP's version starts with the OCCT version it binds;
    'OpenCASCADE: OCP not importable' when it cannot be loaded."""
    try:
        import OCP
    except ImportError:
        return "OpenCASCADE: OCP not importable"
    ocp = str(OCP.__version__)
    return f"OpenCASCADE {'.'.join(ocp.split('.')[:3])} (OCP {ocp})"
