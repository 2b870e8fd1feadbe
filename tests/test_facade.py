"""The top-level facade: lazy names that are the library's functions, one-line reprs."""

import subprocess
import sys

import pytest

import medax
from medax.geometry.region_io import read_region, sample_regions_path
from medax.samples import sample_path

NUMPY_NAMES = ("trace_axis", "mesh_region")
CAD_NAMES = ("read_part", "classify", "simplify", "write_step", "mesh_part")


def fresh(code: str) -> str:
    """stdout of ``code`` run in a new interpreter (a clean ``sys.modules``)."""
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return run.stdout.strip()


def test_import_and_numpy_facade_stay_free_of_occt_and_gmsh():
    out = fresh(
        "import sys, medax\n"
        "light = not {'OCP', 'gmsh'} & set(sys.modules)\n"
        "medax.trace_axis, medax.mesh_region\n"
        "print(light, 'OCP' in sys.modules, 'gmsh' in sys.modules)"
    )
    assert out == "True False False"


def test_names_are_the_library_functions():
    from medax.axis import trace_axis
    from medax.cad import facade
    from medax.cad.part_mesh import mesh_part
    from medax.cad.reader import read_part
    from medax.cad.simplify.step_out import write_step
    from medax.mesh.mesher import mesh_region

    assert medax.trace_axis is trace_axis and medax.mesh_region is mesh_region
    assert medax.read_part is read_part and medax.write_step is write_step
    assert medax.mesh_part is mesh_part
    assert medax.classify is facade.classify and medax.simplify is facade.simplify
    assert set(NUMPY_NAMES + CAD_NAMES) == set(medax._LAZY)
    assert set(medax._LAZY) <= set(medax.__all__) <= set(dir(medax))
    with pytest.raises(AttributeError, match="no attribute 'mesh_face'"):
        _ = medax.mesh_face


def one_line(obj: object, *words: str) -> str:
    text = repr(obj)
    assert "\n" not in text and len(text) < 200, text
    assert all(w in text for w in words), text
    return text


def test_axis_and_mesh_reprs():
    region = read_region(sample_regions_path(), "wavy")
    axis = medax.trace_axis(region, pair=(0, 2))
    one_line(axis, "wavy", f"{axis.n_points} points", "x diagonal")
    one_line(medax.mesh_region(region, divisions=(8, 4)), "8x4 quads", "45 nodes")


def test_classify_accepts_a_path_a_part_or_a_solid():
    path = sample_path("filleted-boss.step")
    part = medax.read_part(path)
    one_line(part, "1 solids", "mm")
    (by_path,) = medax.classify(path)
    (by_part,) = medax.classify(part)
    (by_solid,) = medax.classify(part.solids[0])
    assert by_path.counts() == by_part.counts() == by_solid.counts()
    one_line(by_path, "11 faces", "2 fillet", "6 protection")


@pytest.mark.slow
def test_simplify_takes_a_classification_and_writes(tmp_path):
    (c,) = medax.classify(sample_path("box-12-edges.step"))
    r = medax.simplify(c)
    one_line(r, "faces 26 -> 6", "20 blends removed", "0 kept", "valid True")
    assert medax.write_step(r.shape, tmp_path / "s.step").stat().st_size > 0


def test_part_mesh_repr():
    part = medax.read_part(sample_path("l-bracket.step"))
    one_line(medax.mesh_part(part.solids[0], 3.0), "quads", "faces structured")


def test_ocp_is_imported_only_in_the_cad_package():
    """Every ``import OCP`` / ``from OCP...`` in the package is under ``medax/cad/`` (the
    numpy core and the CLI reach OpenCASCADE only through it)."""
    import ast
    from pathlib import Path

    import medax

    root = Path(medax.__file__).parent
    offenders = []
    for path in root.rglob("*.py"):
        if path.relative_to(root).parts[0] == "cad":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else []
            )
            if any(n == "OCP" or n.startswith("OCP.") for n in names):
                offenders.append(f"{path.relative_to(root)}:{node.lineno}")
    assert offenders == []
