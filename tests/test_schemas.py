"""Every JSON file medax reads or writes validates against its packaged JSON Schema, and every
output carries the header (version, schema version, kind, units, tolerances)."""

import json
from importlib import resources
from pathlib import Path

import jsonschema
import pytest

from medax import __version__
from medax.cli.main import main
from medax.samples import sample_path
from medax.schemas import COMMON, SCHEMA_VERSION, SCHEMAS, schema, stamp, validation_errors

REGIONS = str(sample_path("regions.json"))


def test_every_schema_is_valid_draft_2020_12_and_listed():
    shipped = {
        p.name for p in resources.files("medax.schemas").iterdir() if p.name.endswith(".json")
    }
    assert shipped == {COMMON, *SCHEMAS.values()}
    ids = set()
    for kind in ["common", *SCHEMAS]:
        s = schema(kind)
        assert s["$schema"] == "https://json-schema.org/draft/2020-12/schema"
        jsonschema.Draft202012Validator.check_schema(s)
        ids.add(s["$id"])
    assert len(ids) == len(SCHEMAS) + 1
    header_kinds = schema("common")["$defs"]["header"]["properties"]["kind"]["enum"]
    assert set(header_kinds) == set(SCHEMAS) - {"regions"}


def test_packaged_regions_file_validates():
    data = json.loads(Path(REGIONS).read_text())
    assert validation_errors(data, "regions") == []
    data["wavy"]["sides"][0] = {"kind": "spiral"}
    assert validation_errors(data, "regions")


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    """Real outputs of every command that writes JSON, on the packaged samples."""
    d = tmp_path_factory.mktemp("outputs")
    boss, bracket = str(sample_path("filleted-boss.step")), str(sample_path("l-bracket.step"))
    runs = {
        "axis-one.json": ["axis", REGIONS, "--region", "wavy", "-o"],
        "axis-both.json": ["axis", REGIONS, "--region", "arcs", "--pair", "both", "-o"],
        "mesh.json": ["mesh", REGIONS, "--region", "wavy", "--divisions", "8,8", "-o",
                      str(d / "m.vtu"), "--report"],
        "classes.json": ["classify", boss, "--report"],
        "view3d.json": ["classify", boss, "--view3d"],
        "view3d-simple.json": ["simplify", boss, "-o", str(d / "s2.step"), "--view3d"],
        "simplify.json": ["simplify", boss, "-o", str(d / "s.step"), "--report"],
        "part.json": ["mesh", bracket, "--size", "5", "-o", str(d / "p.msh"), "--report"],
    }  # fmt: skip
    for name, argv in runs.items():
        assert main([*argv, str(d / name)]) == 0, name
    return d


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "kind", "unit"),
    [
        ("axis-one.json", "axis", "mm"),
        ("axis-both.json", "axis", "mm"),
        ("mesh.json", "mesh-report", "mm"),
        ("classes.json", "classify-report", "mm"),
        ("view3d.json", "view3d", "mm"),
        ("view3d-simple.json", "view3d", "mm"),
        ("simplify.json", "simplify-report", "mm"),
        ("part.json", "part-mesh-report", "mm"),
    ],
)
def test_command_output_validates(outputs, name, kind, unit):
    data = json.loads((outputs / name).read_text())
    assert validation_errors(data, kind) == []
    for record in data if isinstance(data, list) else [data]:
        assert record["medax_version"] == __version__
        assert record["schema_version"] == SCHEMA_VERSION and record["kind"] == kind
        assert record["units"]["length"] == unit
        assert record["tolerances"] and all(v > 0 for v in record["tolerances"].values())


def test_several_solids_validate(outputs):
    """The multi-solid layouts (built from real single-solid reports)."""
    from medax.cli.simplify import _combine

    one = json.loads((outputs / "simplify.json").read_text())
    header = ("medax_version", "schema_version", "kind", "units", "tolerances")
    extra = ("input", "output", "written_file")
    solid = {k: v for k, v in one.items() if k not in (*header, *extra)}
    two = stamp("simplify-report", _combine([solid, solid]), "mm", one["tolerances"])
    two |= {k: one[k] for k in extra}
    assert validation_errors(two, "simplify-report") == []
    part = json.loads((outputs / "part.json").read_text())
    solid = {k: v for k, v in part.items() if k not in header and k != "total_time_s"}
    two = stamp("part-mesh-report", {"solids": [solid, solid]}, "mm", part["tolerances"])
    assert validation_errors(two | {"total_time_s": 1.0}, "part-mesh-report") == []


def test_a_broken_output_is_named_where_it_breaks(outputs):
    data = json.loads((outputs / "axis-both.json").read_text())
    del data[1]["points"]
    data[0]["pair"] = [0, 5]
    assert validation_errors(data, "axis") == [
        "$[0].pair[1]: 5 is greater than the maximum of 3",
        "$[1]: 'points' is a required property",
    ]
    report = json.loads((outputs / "simplify.json").read_text())
    del report["tolerances"]
    assert validation_errors(report, "simplify-report") == [
        "$: 'tolerances' is a required property"
    ]


def test_region_units_default_to_unspecified(tmp_path):
    spec = json.loads(Path(REGIONS).read_text())
    del spec["_units"]
    src, out = tmp_path / "r.json", tmp_path / "a.json"
    src.write_text(json.dumps(spec))
    assert main(["axis", str(src), "--region", "trapezoid", "-o", str(out)]) == 0
    assert json.loads(out.read_text())["units"] == {"length": "unspecified"}


def test_stamp_refuses_an_unknown_kind():
    with pytest.raises(ValueError, match="unknown output kind"):
        stamp("regions", {}, "mm", {})


def test_simplify_report_without_a_fit_volume_estimate_is_json():
    """A fitted face whose side of the solid cannot be told has no volume estimate (NaN):
    the report says null, not a non-JSON NaN (a 708-face corpus part failed to write its
    report after the whole run)."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

    from medax.cad.simplify.pipeline import SimplifyResult

    box = BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape()
    r = SimplifyResult(box, 6, 6, [], [], True, 6.0, 6.0, 0.0, 3.7, [], 0.1)
    r = SimplifyResult(**{**r.__dict__, "fit_volume_rel_change": float("nan")})
    report = json.loads(json.dumps(r.report(), allow_nan=False))
    assert report["fit_volume_rel_change"] is None
    from medax.cli.simplify import simplify_tolerances

    written = {"solids": 1, "faces": 6, "valid": True, "max_deviation": 0.0}
    written |= {"allowed_deviation": 3.7e-5, "default_integrator_volume_rel_change": 0.0}
    report.update(input="in.step", output="out.step", written_file=written)
    full = stamp("simplify-report", report, "mm", simplify_tolerances(1e-5), time="s")
    assert validation_errors(full, "simplify-report") == []
