"""The JSON files medax reads and writes: their header and their JSON Schemas.

Every JSON file medax writes starts with the same header (:func:`stamp`): ``medax_version``,
``schema_version``, ``kind`` (which schema applies), ``units`` and the ``tolerances`` the run
used. The schemas (JSON Schema draft 2020-12) ship in this package, one per kind; see
``docs/formats.md``. Validation needs the optional ``jsonschema`` package (a dev
dependency); nothing else here does.
"""

from __future__ import annotations

import json
from functools import cache
from importlib import resources
from typing import Any

from medax import __version__
from medax.errors import InputError

#: Raised when a file's layout changes incompatibly; readers compare it to their own.
SCHEMA_VERSION = 1

#: kind -> schema file in this package (``regions`` is an input and carries no header)
SCHEMAS = {
    "regions": "regions.schema.json",
    "axis": "axis.schema.json",
    "mesh-report": "mesh-report.schema.json",
    "part-mesh-report": "part-mesh-report.schema.json",
    "classify-report": "classify-report.schema.json",
    "simplify-report": "simplify-report.schema.json",
    "batch-record": "batch-record.schema.json",
    "batch-summary": "batch-summary.schema.json",
    "view3d": "view3d.schema.json",
}
#: the shared definitions (header, statistics) the other schemas refer to
COMMON = "common.schema.json"


def stamp(
    kind: str,
    data: dict[str, Any],
    length_unit: str,
    tolerances: dict[str, float],
    **units: str,
) -> dict[str, Any]:
    """``data`` with the header first: version, schema version, ``kind``, units
    (``length`` plus ``units``, e.g. ``angle="deg"``, ``time="s"``) and ``tolerances``."""
    if kind not in SCHEMAS or kind == "regions":
        raise ValueError(f"unknown output kind '{kind}'")
    header: dict[str, Any] = {
        "medax_version": __version__,
        "schema_version": SCHEMA_VERSION,
        "kind": kind,
        "units": {"length": length_unit, **units},
        "tolerances": dict(tolerances),
    }
    return header | {k: v for k, v in data.items() if k not in header}


def schema_text(name: str) -> str:
    """The text of a packaged schema file (``axis.schema.json``, ``common.schema.json``)."""
    if name not in (COMMON, *SCHEMAS.values()):
        raise InputError(f"no schema named '{name}' (known: {', '.join(SCHEMAS)})")
    return (resources.files(__name__) / name).read_text(encoding="utf-8")


@cache
def schema(kind: str) -> dict[str, Any]:
    """The parsed JSON Schema of ``kind`` (a key of :data:`SCHEMAS`, or ``"common"``)."""
    name = COMMON if kind == "common" else SCHEMAS.get(kind)
    if name is None:
        raise InputError(f"no schema for '{kind}' (known: {', '.join(SCHEMAS)})")
    result: dict[str, Any] = json.loads(schema_text(name))
    return result


def validation_errors(data: Any, kind: str) -> list[str]:
    """Every way ``data`` breaks the schema of ``kind``, one line each (``[]``: valid).

    Needs ``jsonschema`` (``pip install 'medax[dev]'``)."""
    validator = _validator(kind)  # first: a clear error when jsonschema is missing
    from jsonschema.exceptions import best_match

    lines = []
    for err in validator.iter_errors(data):
        while err.context:  # a oneOf / anyOf: the branch that came closest
            err = best_match(err.context)
        lines.append(f"{err.json_path}: {err.message[:200]}")
    return sorted(lines)


def _validator(kind: str) -> Any:
    try:
        import jsonschema
        import referencing
        from referencing.jsonschema import DRAFT202012
    except ImportError:  # pragma: no cover - a dev dependency
        raise InputError(
            "validating needs the jsonschema package (pip install 'medax[dev]')"
        ) from None
    common = schema("common")
    registry = referencing.Registry().with_resource(
        common["$id"], DRAFT202012.create_resource(common)
    )
    cls = jsonschema.Draft202012Validator
    cls.check_schema(schema(kind))
    return cls(schema(kind), registry=registry, format_checker=cls.FORMAT_CHECKER)
