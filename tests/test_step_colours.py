"""STEP outputs with a colour and a name per face (XCAF): read back with OCCT's XCAF reader
and checked against what each face is, told from its geometry in the file (a fillet is a
cylinder, a corner blend a sphere, ...), not from medax's classification."""

from __future__ import annotations

import re

import numpy as np
import pytest
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.GeomAbs import GeomAbs_Cylinder, GeomAbs_Plane, GeomAbs_Sphere
from OCP.TopoDS import TopoDS

from medax.cad.simplify import parts as P
from medax.cad.simplify.step_out import write_step
from medax.cad.xcaf import read_styled_step
from medax.cli.main import main
from medax.viz.before_after import GREY, group_colour
from medax.viz.view3d import CLASS_COLOURS

pytestmark = pytest.mark.slow


def _kind(face):
    """'plane', 'cylinder', 'sphere' or 'other', and the plane's normal / the radius."""
    s = BRepAdaptor_Surface(TopoDS.Face(face))
    t = s.GetType()
    if t == GeomAbs_Plane:
        d = s.Plane().Axis().Direction()
        return "plane", np.array([d.X(), d.Y(), d.Z()])
    if t == GeomAbs_Cylinder:
        return "cylinder", s.Cylinder().Radius()
    if t == GeomAbs_Sphere:
        return "sphere", s.Sphere().Radius()
    return "other", None


def _close(rgb, want):
    return rgb is not None and np.allclose(rgb, want, atol=2e-6)


@pytest.fixture(scope="module")
def parts(tmp_path_factory):
    d = tmp_path_factory.mktemp("in")
    paths = {}
    for name, built in (("box4", P.box_vertical_fillets()), ("box12", P.box_all_fillets())):
        paths[name] = d / f"{name}.step"
        write_step(built.shape, paths[name])
    return paths


def test_classify_step_colours_and_names(parts, tmp_path):
    out = tmp_path / "classes.step"
    assert main(["-q", "classify", str(parts["box12"]), "--no-axes", "--step", str(out)]) == 0
    shape, faces = read_styled_step(out)
    assert len(faces) == 26
    kinds = [_kind(f.face) for f in faces]
    assert sorted(k for k, _ in kinds) == ["cylinder"] * 12 + ["plane"] * 6 + ["sphere"] * 8
    seen = set()
    for f, (kind, value) in zip(faces, kinds, strict=True):
        m = re.fullmatch(r"(fillet|corner blend|supporting|protection) (\d+)( r=([\d.]+))?", f.name)
        assert m, f.name
        seen.add(int(m.group(2)))
        cls = {"cylinder": "fillet", "sphere": "corner_blend", "plane": "supporting"}[kind]
        assert m.group(1) == cls.replace("_", " "), (f.name, kind)
        assert _close(f.rgb, CLASS_COLOURS[cls]), (f.name, f.rgb)
        if kind != "plane":  # the radius in the name is the surface's
            assert abs(float(m.group(4)) - value) < 1e-9, f.name
        else:
            assert m.group(3) is None
    assert seen == set(range(26))  # every face index once


def test_classify_step_protection(parts, tmp_path):
    """4 vertical fillets: the side planes support them, top and bottom (normal along the
    fillets' axes, met at the cross edges) are protection faces."""
    out = tmp_path / "classes.step"
    assert main(["-q", "classify", str(parts["box4"]), "--no-axes", "--step", str(out)]) == 0
    _, faces = read_styled_step(out)
    for f in faces:
        kind, value = _kind(f.face)
        if kind == "cylinder":
            want = "fillet"
        else:
            assert kind == "plane"
            want = "protection" if abs(value[2]) > 0.99 else "supporting"
        assert f.name.startswith(want + " "), (f.name, kind)
        assert _close(f.rgb, CLASS_COLOURS[want])


def test_simplify_step_colours_by_group(parts, tmp_path):
    """4 vertical fillets removed: each side face absorbed the halves of its two fillets
    (its own colour, named by the input faces it came from); top and bottom are untouched
    (grey). The written file still passes simplify's read-back check."""
    from medax.cad.reader import read_part

    out = tmp_path / "simple.step"
    assert main(["-q", "simplify", str(parts["box4"]), "-o", str(out)]) == 0
    (solid_in,) = read_part(parts["box4"]).solids
    from medax.cad.simplify.occ import faces_of

    kinds_in = [_kind(f) for f in faces_of(solid_in)]
    shape, faces = read_styled_step(out)
    assert len(faces) == 6
    colours = []
    for f in faces:
        kind, normal = _kind(f.face)
        assert kind != "cylinder"  # fillets gone
        if kind == "plane" and abs(normal[2]) > 0.99:
            assert re.fullmatch(r"face \d+", f.name), f.name
            assert _close(f.rgb, GREY)
            continue
        m = re.fullmatch(r"merged from faces ([\d,]+) \(fillet halves ([\d,]+)\)", f.name)
        assert m, f.name
        members = [int(i) for i in m.group(1).split(",")]
        halves = [int(i) for i in m.group(2).split(",")]
        # the input faces named: the two fillets beside it and one plane facing the same way
        assert len(halves) == 2 and all(kinds_in[i][0] == "cylinder" for i in halves)
        (plane,) = sorted(set(members) - set(halves))
        assert kinds_in[plane][0] == "plane"
        n_in = kinds_in[plane][1]
        if kind == "plane":
            assert abs(abs(float(np.dot(n_in, normal))) - 1.0) < 1e-9
        colours.append(f.rgb)
    assert len(colours) == 4
    assert all(any(_close(c, group_colour(k)) for c in colours) for k in range(4))


def test_simplify_step_highlights_kept_blends(tmp_path):
    """Two fillets meeting in a mitre: one is kept (the only cylinder left: black, named
    with its radius and reason), the other merged into its two supporting faces."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

    import medax.cad.parts as catalogue
    from medax.viz.before_after import KEPT

    box = BRepPrimAPI_MakeBox(30.0, 20.0, 10.0).Shape()

    def top_front_right(m):
        return abs(m[2] - 10.0) < 1e-9 and (abs(m[1]) < 1e-9 or abs(m[0] - 30.0) < 1e-9)

    part = catalogue.fillet(box, catalogue._select(box, top_front_right), 2.0, "mitred")
    src, out = tmp_path / "mitred.step", tmp_path / "simple.step"
    write_step(part.shape, src)
    assert main(["-q", "simplify", str(src), "-o", str(out)]) == 0
    _, faces = read_styled_step(out)
    assert len(faces) == 7
    (kept,) = [f for f in faces if _kind(f.face)[0] == "cylinder"]
    m = re.fullmatch(r"kept blend (\d+) r=2: .*meets fillet (\d+) in a mitre.*", kept.name)
    assert m, kept.name
    assert _close(kept.rgb, KEPT)
    removed = m.group(2)
    merged = [f for f in faces if f.name.startswith("merged from faces")]
    assert len(merged) == 2  # the removed fillet's two halves went to its two supports
    assert all(removed in re.search(r"halves ([\d,]+)", f.name).group(1).split(",") for f in merged)
    assert all(not _close(f.rgb, KEPT) and not _close(f.rgb, GREY) for f in merged)


@pytest.mark.parametrize(
    ("option", "name", "why"),
    [
        ("--step", "c.igs", "'.igs' is not a known extension"),
        ("--view3d", "v.txt", "'.txt' is not a known extension"),
    ],
)
def test_new_outputs_are_checked_before_any_work(parts, tmp_path, capsys, option, name, why):
    code = main(["classify", str(parts["box4"]), option, str(tmp_path / name)])
    assert code == 1 and why in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_a_located_solid_keeps_its_styles(tmp_path):
    """A solid placed by a location (as some BRep files hold it): each face still gets its
    colour and name, at its placed position."""
    from OCP.gp import gp_Trsf, gp_Vec
    from OCP.TopLoc import TopLoc_Location

    from medax.cad.simplify.occ import faces_of
    from medax.cad.xcaf import FaceStyle, write_styled_step

    t = gp_Trsf()
    t.SetTranslation(gp_Vec(100.0, 0.0, 0.0))
    solid = P.box_vertical_fillets().shape.Moved(TopLoc_Location(t))
    assert not solid.Location().IsIdentity()
    styles = []
    for k, face in enumerate(faces_of(solid)):
        rgb = CLASS_COLOURS["fillet"] if _kind(face)[0] == "cylinder" else GREY
        styles.append(FaceStyle(face, rgb, f"face {k}"))
    out = tmp_path / "located.step"
    write_styled_step(solid, out, styles, "located")
    _, faces = read_styled_step(out)
    assert [f.name for f in faces] == [s.name for s in styles]
    for f in faces:
        want = CLASS_COLOURS["fillet"] if _kind(f.face)[0] == "cylinder" else GREY
        assert _close(f.rgb, want)
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(faces[0].face, box)
    assert box.CornerMin().X() >= 100.0 - 1e-6  # placed, not at the origin
    # a compound of the placed solid and an unplaced one (two solids of a part)
    from medax.cad.simplify.occ import compound

    other = P.box_all_fillets().shape
    both = compound([solid, other])
    more = [
        FaceStyle(f, CLASS_COLOURS["supporting"], f"other {k}")
        for k, f in enumerate(faces_of(other))
    ]
    write_styled_step(both, out, styles + more, "two")
    _, faces = read_styled_step(out)
    assert sorted(f.name for f in faces) == sorted(s.name for s in styles + more)
    for f in faces:
        want = CLASS_COLOURS["supporting"] if f.name.startswith("other") else GREY
        if _kind(f.face)[0] == "cylinder" and not f.name.startswith("other"):
            want = CLASS_COLOURS["fillet"]
        assert _close(f.rgb, want), f.name
