"""Read 4-sided planar regions from the JSON format of ``regions.json``.

A file maps region names to ``{"corners": [[x, y] x 4], "sides": [side x 4]}``; a side is
``{"kind": "line"}``, ``{"kind": "arc", "sagitta": h}`` or ``{"kind": "arc", "center":
[x, y], "radius": r}``, ``{"kind": "bspline", "degree": p, "points": [[x, y], ...]}`` or
``{"kind": "polyline", "points": [[x, y], ...]}``. Keys starting with ``_`` are metadata;
``_units`` names the length unit of the coordinates (copied into the outputs' header).
"""

from __future__ import annotations

import json
import math
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from medax.errors import CurveError, InputError, RegionError
from medax.geometry.arc import Arc
from medax.geometry.bspline import BSpline
from medax.geometry.curve import Curve
from medax.geometry.line import Line
from medax.geometry.polyline import Polyline
from medax.geometry.region import Region

SIDE_KINDS = ("line", "arc", "bspline", "polyline")
"""The side kinds of the format."""


def sample_regions_path() -> Path:
    """Give the path of the sample ``regions.json`` shipped inside the package."""
    return Path(str(resources.files("medax") / "data" / "regions.json"))


def load_region_file(path: str | Path) -> dict[str, Any]:
    """Load the raw JSON mapping of a regions file.

    Parameters
    ----------
    path : str or Path
        The regions file.

    Returns
    -------
    dict
        Region names (and ``_`` metadata keys) to their JSON objects, unchecked.

    Raises
    ------
    InputError
        A missing file, not text, malformed JSON or not a JSON object.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such file")
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except UnicodeDecodeError as err:
        raise InputError(f"{p}: not a text file ({err.reason})") from err
    except json.JSONDecodeError as err:
        raise InputError(f"{p}: malformed JSON at line {err.lineno}: {err.msg}") from err
    except RecursionError:
        raise InputError(f"{p}: JSON nested too deeply to be a regions file") from None
    except ValueError as err:  # e.g. an integer of more than 4300 digits
        raise InputError(f"{p}: malformed JSON ({err})") from None
    if not isinstance(data, dict):
        raise InputError(f"{p}: expected a JSON object mapping region names to regions")
    return data


def region_names(data: dict[str, Any]) -> list[str]:
    """List the region names of a loaded regions file.

    Parameters
    ----------
    data : dict
        The mapping from [load_region_file][medax.geometry.region_io.load_region_file].

    Returns
    -------
    list of str
        The names in file order, metadata keys starting with ``_`` skipped.
    """
    return [k for k in data if not k.startswith("_")]


def length_unit(data: dict[str, Any]) -> str:
    """Give the length unit a loaded regions file names in ``_units``.

    Parameters
    ----------
    data : dict
        The mapping from [load_region_file][medax.geometry.region_io.load_region_file].

    Returns
    -------
    str
        The unit, ``"unspecified"`` when it names none.
    """
    unit = data.get("_units")
    return unit if isinstance(unit, str) and unit.strip() else "unspecified"


def read_region(path: str | Path, name: str) -> Region:
    """Read one region of a regions file.

    Parameters
    ----------
    path : str or Path
        The regions file.
    name : str
        The region's name.

    Returns
    -------
    Region
        The region, checked and counter-clockwise ([Region][medax.geometry.region.Region]).

    Raises
    ------
    InputError
        The file cannot be loaded or holds no region ``name`` (the message lists them).
    RegionError
        The region is not valid (open corner, zero-length or crossing sides).
    CurveError
        A side definition is not valid.
    """
    data = load_region_file(path)
    if name not in region_names(data):
        known = ", ".join(region_names(data)) or "none"
        raise InputError(f"{path}: no region named '{name}' (regions: {known})")
    return region_from_dict(data[name], name)


def read_regions(path: str | Path) -> dict[str, Region]:
    """Read all regions of a regions file.

    Parameters
    ----------
    path : str or Path
        The regions file.

    Returns
    -------
    dict of str to Region
        The regions by name, in file order.

    Raises
    ------
    InputError
        As [read_region][medax.geometry.region_io.read_region] (including its subclasses
        ``RegionError`` and ``CurveError``).
    """
    data = load_region_file(path)
    return {n: region_from_dict(data[n], n) for n in region_names(data)}


def region_from_dict(spec: Any, name: str) -> Region:
    """Build a region from one JSON region object.

    Parameters
    ----------
    spec : dict
        ``{"corners": [[x, y] x 4], "sides": [side x 4]}`` (see the module's description).
    name : str
        Names the region in messages.

    Returns
    -------
    Region
        The region, checked and counter-clockwise ([Region][medax.geometry.region.Region]).

    Raises
    ------
    RegionError
        Corners or sides missing or malformed, or the region is not valid.
    CurveError
        A side definition is not valid.
    """
    if not isinstance(spec, dict) or "corners" not in spec or "sides" not in spec:
        raise RegionError(f"region '{name}': needs 'corners' and 'sides'")
    corners = _points(spec["corners"], f"region '{name}': corners", RegionError)
    if corners.shape != (4, 2):
        raise RegionError(f"region '{name}': needs 4 corners [x, y], got shape {corners.shape}")
    sides_spec = spec["sides"]
    if not isinstance(sides_spec, list) or len(sides_spec) != 4:
        raise RegionError(f"region '{name}': needs a list of 4 sides")
    sides = [_side(sides_spec[k], corners[k], corners[(k + 1) % 4], name, k) for k in range(4)]
    return Region.build(sides, name=name)


def _points(value: Any, what: str, error: type[InputError] = CurveError) -> np.ndarray:
    """``value`` as a finite float array; ``error`` naming ``what`` otherwise."""
    if isinstance(value, str | bool | dict) or value is None:
        raise error(f"{what} must be numbers, got {type(value).__name__}")
    try:
        arr = np.asarray(value, dtype=np.float64)
    except OverflowError:
        raise error(f"{what}: a number is too large for a float") from None
    except (TypeError, ValueError):
        raise error(f"{what} must be lists of numbers [x, y]") from None
    if not np.all(np.isfinite(arr)):
        raise error(f"{what} must be finite numbers (NaN, infinity or overflow found)")
    return arr


def _number(value: Any, what: str) -> float:
    """``value`` as a finite float (a JSON number, not a string or boolean)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise CurveError(f"{what} must be a number, got {json.dumps(value)[:40]}")
    try:
        x = float(value)
    except OverflowError:
        raise CurveError(f"{what} is too large for a float") from None
    if not math.isfinite(x):
        raise CurveError(f"{what} must be finite, got {x}")
    return x


def _degree(value: Any, n_points: int) -> int:
    """A B-spline degree: an integer from 1 to ``n_points - 1``."""
    top = n_points - 1
    ok = not isinstance(value, bool) and isinstance(value, int | float)
    if ok and isinstance(value, float):
        ok = math.isfinite(value) and value.is_integer()
    if not ok or not 1 <= value <= top:
        shown = json.dumps(value)[:40] if not isinstance(value, float) else repr(value)
        raise CurveError(
            f"degree must be an integer from 1 to {top} ({n_points} points), got {shown}"
        )
    return int(value)


def _side(spec: Any, p0: np.ndarray, p1: np.ndarray, name: str, k: int) -> Curve:
    where = f"region '{name}' side {k}"
    if not isinstance(spec, dict) or "kind" not in spec:
        raise CurveError(f"{where}: needs a 'kind'")
    kind = spec["kind"]
    try:
        if kind == "line":
            return Line(p0, p1)
        if kind == "arc":
            if "sagitta" in spec:
                return Arc.from_sagitta(p0, p1, _number(spec["sagitta"], "sagitta"))
            if "center" in spec and "radius" in spec:
                center = _points(spec["center"], "center")
                if center.shape != (2,):
                    raise CurveError(f"center must be [x, y], got shape {center.shape}")
                return Arc.from_center(p0, p1, center, _number(spec["radius"], "radius"))
            raise CurveError("an arc needs 'sagitta', or 'center' and 'radius'")
        if kind in ("bspline", "polyline"):
            pts = _points(spec.get("points"), "'points'")
            if pts.ndim != 2 or pts.shape[0] < 2 or pts.shape[1] != 2:
                raise CurveError(f"'points' must be a list of [x, y], got shape {pts.shape}")
            for end, corner, which in ((pts[0], p0, "first"), (pts[-1], p1, "last")):
                if np.linalg.norm(end - corner) > 1e-9 * max(1.0, float(np.abs(corner).max())):
                    raise CurveError(
                        f"{which} point {end.tolist()} is not corner {corner.tolist()}"
                    )
            if kind == "polyline":
                return Polyline(pts)
            return BSpline(pts, _degree(spec.get("degree", 3), len(pts)))
    except CurveError as err:
        raise CurveError(f"{where}: {err}") from err
    except (TypeError, ValueError, OverflowError, ZeroDivisionError) as err:
        raise CurveError(f"{where}: bad {kind} definition ({err})") from err
    raise CurveError(f"{where}: unknown side kind '{kind}' (known: {', '.join(SIDE_KINDS)})")
