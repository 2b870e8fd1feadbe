"""Quad meshes of whole CAD parts built with OCCT (the 26 -> 6 simplified box, an L-bracket,
a plate with a boss and a hole, a stepped shaft).

Truth: OCCT's own distances (``BRepExtrema_DistShapeShape`` from every node to its CAD face),
the mesh's own incidence (every mesh edge in exactly two quads on a closed solid, no two
nodes within 1e-9 x diagonal), the outward normal OCCT gives for the face
(``BRepLProp_SLProps`` at the node's projection, reversed faces flipped), and the files read
back by meshio and by gmsh.
"""

from __future__ import annotations

import json

import gmsh
import meshio
import numpy as np
import pytest
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Pnt
from OCP.TopAbs import TopAbs_REVERSED
from scipy.spatial import cKDTree

from medax.cad import parts
from medax.cad.edge_counts import division_counts
from medax.cad.face_region import face_region, face_sides, not_four_sided
from medax.cad.part_mesh import mesh_part
from medax.cad.simplify import parts as sparts
from medax.cad.simplify import simplify, specs_from_blend_faces
from medax.cad.topology import build_topology
from medax.errors import CadError
from medax.mesh.grouped_export import MeshGroups, write_grouped_mesh
from medax.mesh.quality import quad_quality
from medax.schemas import validation_errors

SIZE = 3.0


BUILT = ("l_bracket", "plate_with_boss", "stepped_shaft")
_CACHE: dict[str, tuple] = {}


def _meshed(name: str) -> tuple:
    """(shape, mesh) of a test part, made once per session."""
    if name not in _CACHE:
        if name == "box6":
            part = sparts.box_all_fillets(40.0, 30.0, 20.0, 4.0)
            r = simplify(part.shape, specs_from_blend_faces(part.shape, part.blends))
            assert (r.faces_before, r.faces_after) == (26, 6)
            shape = r.shape
        else:
            shape = getattr(parts, name)().shape
        _CACHE[name] = (shape, mesh_part(shape, SIZE))
    return _CACHE[name]


@pytest.fixture(scope="module")
def box6():
    return _meshed("box6")


@pytest.fixture(scope="module", params=BUILT)
def built(request):
    return _meshed(request.param)


@pytest.fixture(scope="module", params=("box6", *BUILT))
def any_part(request):
    return _meshed(request.param)


def _face_nodes(mesh, i):
    return np.unique(mesh.quads[mesh.quad_face == i])


@pytest.mark.slow
def test_box6_all_faces_structured(box6):
    _, m = box6
    assert len(m.structured_faces) == 6 and not m.conflicts
    # every edge an even count (the medial split halves them); each box edge is a chain of
    # a corner piece, the medial line and a corner piece: 2 divisions on the corner pieces,
    # one count per box direction on the lines
    counts = m.edge_counts.tolist()
    assert all(c % 2 == 0 for c in counts) and len(set(counts) - {2}) == 3


def test_built_parts_mix_structured_and_gmsh(built):
    _, m = built
    assert len(m.gmsh_faces) >= 1  # faces with holes or seams
    for f in m.faces:
        assert (f.kind == "structured") == (f.divisions is not None)
        assert f.kind == "structured" or f.why


@pytest.mark.slow
def test_nodes_on_their_faces(any_part):
    """Every node within 1e-9 x diagonal of its CAD face (BRepExtrema on the trimmed face;
    measured: at most 4e-16, also on the simplified box's fitted faces)."""
    shape, m = any_part
    topo = build_topology(shape)
    tol = 1e-9 * m.diagonal
    for i in np.unique(m.quad_face).tolist():
        face = topo.face(i)
        for k in _face_nodes(m, i).tolist():
            v = BRepBuilderAPI_MakeVertex(gp_Pnt(*m.points[k])).Vertex()
            d = BRepExtrema_DistShapeShape(v, face)
            assert d.IsDone() and d.Value() <= tol, (i, k, d.Value())


def test_shared_nodes_and_closed(any_part):
    _, m = any_part
    assert not cKDTree(m.points).query_pairs(1e-9 * m.diagonal)
    e = np.sort(np.stack([m.quads, np.roll(m.quads, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    assert np.all(counts == 2)  # closed: no hanging node, no open or non-manifold edge
    # every edge's line elements join the nodes of the quads on both of its faces
    quad_edges = {tuple(x) for x in e.tolist()}
    assert all(tuple(sorted(seg)) in quad_edges for seg in m.lines.tolist())


@pytest.mark.slow
def test_quads_face_outward(any_part):
    """At each quad corner the turn ``L_{k-1} x L_k`` points along OCCT's outward normal of
    the face there (no inverted or flat corner)."""
    shape, m = any_part
    topo = build_topology(shape)
    for i in np.unique(m.quad_face).tolist():
        face = topo.face(i)
        q = m.quads[m.quad_face == i]
        surf = BRep_Tool.Surface_s(face)
        ad = BRepAdaptor_Surface(face)
        sign = -1.0 if face.Orientation() == TopAbs_REVERSED else 1.0
        nodes = np.unique(q)
        normal = np.zeros((len(m.points), 3))
        for k in nodes.tolist():
            proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*m.points[k]), surf)
            u, v = proj.LowerDistanceParameters()
            props = BRepLProp_SLProps(ad, u, v, 1, 1e-9)
            n = props.Normal()
            normal[k] = sign * np.array([n.X(), n.Y(), n.Z()])
        p = m.points[q]
        edges = np.roll(p, -1, axis=1) - p
        turn = np.cross(np.roll(edges, 1, axis=1), edges)
        area = np.einsum("mkd,mkd->mk", turn, normal[q])
        assert np.all(area > 0.0), (i, int(np.sum(area <= 0)))


def test_quality_of_structured_box(box6):
    _, m = box6
    sj = quad_quality(m.points, m.quads).scaled_jacobian
    # a rounded box's faces: near-rectangular grids (0.879 at worst, where the corner
    # pieces' 2 divisions meet a side's coarser spacing)
    assert sj.min() > 0.85


def test_groups_read_back(tmp_path, built):
    """msh read by gmsh and meshio with a physical surface per face and a physical curve
    per edge; inp with ELSET/NSET; vtu with group cell data; bdf with a PID per face."""
    _, m = built
    faces = np.unique(m.quad_face).tolist()
    edges = np.unique(m.line_edge).tolist()
    g = MeshGroups(
        m.quad_face,
        {i: f"face_{i}" for i in faces},
        m.lines,
        m.line_edge,
        {j: f"edge_{j}" for j in edges},
    )
    q = quad_quality(m.points, m.quads).as_dict()
    for ext in ("msh", "vtu", "inp", "bdf"):
        write_grouped_mesh(tmp_path / f"p.{ext}", m.points, m.quads, g, q)
    r = meshio.read(tmp_path / "p.msh")
    assert {f"face_{i}" for i in faces} | {f"edge_{j}" for j in edges} == set(r.field_data)
    assert len(r.cells_dict["quad"]) == len(m.quads)
    assert len(r.cells_dict["line"]) == len(m.lines)
    # gmsh writes the nodes entity by entity: the same nodes and quads, renumbered
    d, ours = cKDTree(m.points).query(r.points)
    assert d.max() <= 1e-14 * m.diagonal and len(np.unique(ours)) == len(m.points)
    back = np.sort(ours[r.cells_dict["quad"]], axis=1)
    np.testing.assert_array_equal(
        np.unique(back, axis=0), np.unique(np.sort(m.quads, axis=1), axis=0)
    )
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(tmp_path / "p.msh"))
        names = {gmsh.model.getPhysicalName(d, t) for d, t in gmsh.model.getPhysicalGroups()}
        assert names == set(r.field_data)
        tags, _ = gmsh.model.mesh.getNodesForPhysicalGroup(2, faces[0] + 1)
        assert len(tags) == len(_face_nodes(m, faces[0]))
        types, _, _ = gmsh.model.mesh.getElements(2)
        assert list(types) == [3]
        gmsh.clear()
        gmsh.merge(str(tmp_path / "p.bdf"))
        assert len(gmsh.model.getEntities(2)) == len(faces)  # one entity per PID
    finally:
        gmsh.finalize()
    r = meshio.read(tmp_path / "p.inp")
    assert set(r.cell_sets) >= {f"face_{i}" for i in faces}
    assert set(r.point_sets) == {f"edge_{j}" for j in edges}
    sel = m.line_edge == edges[0]
    assert len(r.point_sets[f"edge_{edges[0]}"]) == len(np.unique(m.lines[sel]))
    r = meshio.read(tmp_path / "p.vtu")
    np.testing.assert_array_equal(r.cell_data["surface_group"][0], m.quad_face)


def test_face_region_sides():
    """A 4-sided face of the L-bracket whose long sides are chains of line, arc, line; faces
    with holes, seams or no corner are not 4-sided, and face_region says why."""
    topo = build_topology(parts.l_bracket().shape)
    chained = [i for i in range(topo.n_faces) if not_four_sided(topo.face(i)) is None
               and max(len(s) for s in face_sides(topo.face(i))) == 3]  # fmt: skip
    assert len(chained) == 2  # the two L-shaped ends
    r = face_region(topo.face(chained[0]))
    # side lengths as dense polylines of the exact space sides (Curve.length's quadrature is
    # 1.4e-5 off on these chains: its pieces straddle the C0 knots where line meets arc)
    poly = [r.space_curve(k).sample(200001) for k in range(4)]
    lengths = sorted(float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) for p in poly)
    # ends 8 long; the L's outer chain 27 + 37 + a quarter circle of r = 3, the inner one
    # 19 + 29 + a quarter circle of r = 3 (the concave fillet)
    np.testing.assert_allclose(lengths[:2], [8.0, 8.0], rtol=1e-12)
    quarter = 0.5 * np.pi * 3.0
    np.testing.assert_allclose(lengths[2:], [19.0 + 29.0 + quarter, 64.0 + quarter], rtol=1e-9)
    holed = [
        i for i in range(topo.n_faces) if "inner wires" in (not_four_sided(topo.face(i)) or "")
    ]
    assert len(holed) == 2
    with pytest.raises(CadError, match="not 4-sided: 1 inner wires"):
        face_region(topo.face(holed[0]))


def test_counts_propagate_and_conflict():
    """Union-find over opposite single edges takes each class's largest count; a chain side
    is evened on its coarsest edge; a face whose sides cannot agree is a conflict."""
    lengths = np.array([10.0, 4.0, 10.0, 4.0, 21.0, 4.0])
    # face 0: edges 0..3 (10 x 4); face 1 shares edge 2 and has 4 opposite it
    c = division_counts(lengths, range(6), {0: [[0], [1], [2], [3]], 1: [[2], [3], [4], [5]]}, 1.0)
    assert c.counts.tolist() == [22, 4, 22, 4, 22, 4] and c.structured == (0, 1)
    # side 0 a chain of two edges (10 + 10) against one edge of 12: the single edge grows
    lengths = np.array([10.0, 10.0, 4.0, 12.0, 4.0])
    c = division_counts(lengths, range(5), {0: [[0, 1], [2], [3], [4]]}, 1.0)
    assert c.counts[3] == c.counts[0] + c.counts[1] == 20
    # a face whose side 0 is edge 0 and side 2 is edge 0 + edge 1: never even
    c = division_counts(np.array([5.0, 5.0, 2.0, 2.0]), range(4),
                        {0: [[0], [2], [0, 1], [3]]}, 1.0)  # fmt: skip
    assert c.structured == () and "opposite sides 0 and 2" in c.conflicts[0]


@pytest.mark.slow
def test_cli_part(tmp_path, capsys):
    """``medax mesh PART.brep``: the mesh, a report with both scaled Jacobians per face, the
    plot; --faces meshes a subset (open where the other faces were)."""
    from OCP.BRepTools import BRepTools

    from medax.cli.main import main

    brep = tmp_path / "bracket.brep"
    BRepTools.Write_s(parts.l_bracket().shape, str(brep))
    out, rep, png = tmp_path / "b.msh", tmp_path / "b.json", tmp_path / "b.png"
    assert main(["mesh", str(brep), "--size", "3", "-o", str(out), "--report", str(rep),
                 "--plot", str(png)]) == 0  # fmt: skip
    cap = capsys.readouterr()
    assert "9/11 faces structured" in cap.out and "medax mesh:" in cap.err
    r = json.loads(rep.read_text())
    assert r["n_structured_faces"] == 9 and r["open_mesh_edges"] == 0 and r["n_inverted"] == 0
    assert len(r["faces"]) == 11 and r["share_of_quads"] == 1.0
    for f in r["faces"]:
        assert 0 < f["scaled_jacobian"]["min"] <= 1 and 0 < f["gmsh_scaled_jacobian"]["min"] <= 1
        assert f["kind"] == "structured" or f["why_not_structured"]
    assert png.stat().st_size > 10_000
    sub = tmp_path / "s.vtu"
    assert main(["mesh", str(brep), "--size", "3", "--faces", "1,2", "-o", str(sub)]) == 0
    m = meshio.read(sub)
    assert set(np.unique(m.cell_data["surface_group"][0]).tolist()) == {1, 2}


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ([], "needs --size"),
        (["--size", "3", "--faces", "99"], "face 99 does not exist"),
        (["--size", "3", "--faces", "a"], "face indices"),
        (["--size", "3", "--divisions", "4"], "not allowed with"),
        (["--size", "3", "--method", "paper"], "regions, not to CAD parts"),
        (["--size", "0"], "must be positive"),
    ],
)
def test_cli_part_bad_input(tmp_path, capsys, extra, message):
    from OCP.BRepTools import BRepTools

    from medax.cli.main import main

    brep = tmp_path / "box.brep"
    BRepTools.Write_s(sparts.box_vertical_fillets().shape, str(brep))
    out = tmp_path / "m.msh"
    try:
        code = main(["mesh", str(brep), *extra, "-o", str(out)])
    except SystemExit as err:  # argparse: mutually exclusive options
        code = int(err.code or 0)
    err = capsys.readouterr().err
    assert code != 0 and message in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.brep"]


def test_cli_part_face_failure_writes_nothing(tmp_path, capsys, monkeypatch):
    """A face gmsh cannot mesh fails the whole run with the face's index: no file."""
    from OCP.BRepTools import BRepTools

    import medax.cad.gmsh_faces as gf
    from medax.cli.main import main

    brep = tmp_path / "bracket.brep"
    BRepTools.Write_s(parts.l_bracket().shape, str(brep))
    monkeypatch.setattr(gf, "ATTEMPTS", ())  # gmsh gets no try: the holed faces fail
    out = tmp_path / "b.inp"
    assert main(["mesh", str(brep), "--size", "3", "-o", str(out), "--report",
                 str(tmp_path / "r.json")]) == 1  # fmt: skip
    last = capsys.readouterr().err.strip().splitlines()[-1]  # (progress lines before it)
    assert last.startswith("medax mesh: error: face 0: gmsh could not mesh it")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bracket.brep"]


def test_cli_part_outputs_all_or_none(tmp_path, capsys, monkeypatch):
    """A plot that fails after the mesh and the report were staged: none of the three is
    written, an existing mesh at ``-o`` is left as it was."""
    from OCP.BRepTools import BRepTools

    import medax.viz.part_plot as pp
    from medax.cli.main import main

    brep = tmp_path / "box.brep"
    BRepTools.Write_s(sparts.box_vertical_fillets().shape, str(brep))
    out = tmp_path / "m.msh"
    out.write_text("the user's earlier mesh")

    def fail(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(pp, "plot_part_mesh", fail)
    code = main(["mesh", str(brep), "--size", "5", "-o", str(out), "--report",
                 str(tmp_path / "r.json"), "--plot", str(tmp_path / "p.png")])  # fmt: skip
    assert code != 0 and "No space left" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.brep", "m.msh"]
    assert out.read_text() == "the user's earlier mesh"


def test_orientation_turns_and_refuses():
    """On the top face of a box (outward +z): clockwise quads are turned over; a quad with a
    reflex corner, or with a corner of 180 degrees, is refused, naming the face."""
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox

    from medax.cad.quad_orientation import orient, oriented
    from medax.errors import MeshError

    topo = build_topology(BRepPrimAPI_MakeBox(2.0, 2.0, 1.0).Shape())
    heights = [BRepAdaptor_Surface(topo.face(i)).Plane().Location().Z() for i in range(6)]
    top = next(i for i, z in enumerate(heights) if abs(z - 1.0) < 1e-12)
    face = topo.face(top)
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, 0.3], [2.0, 0.0]])
    pts = np.column_stack((xy, np.ones(len(xy))))
    uv = np.zeros((len(xy), 2))  # (a plane: the normal is the same everywhere)
    q, problem = orient(face, np.array([[0, 3, 2, 1]]), uv, pts)
    assert problem is None and q.tolist() == [[1, 2, 3, 0]]
    dart = np.array([[0, 1, 2, 3], [0, 1, 4, 3]])  # node 4 (0.5, 0.3): a reflex corner
    _, problem = orient(face, dart, uv, pts)
    assert problem is not None and problem.startswith("1 quads inverted or flat")
    flat = np.array([[0, 1, 5, 2]])  # 0, 1, 5 on a line: a corner of 180 degrees at 1
    with pytest.raises(MeshError, match="face 7: 1 quads inverted or flat"):
        oriented(face, 7, flat, uv, pts)


@pytest.mark.slow
def test_demo_part_mesh(tmp_path):
    """The demo meshes the 12-fillet box after --simplify (6 of 6 faces medial) and the
    L-bracket (9 of 11: the hole's cylinder too, cut by its seam), with reports and pictures."""
    from medax.cli.demo_part_mesh import demo

    written = demo(tmp_path)
    assert sorted(p.suffix for p in written) == [".json", ".json", ".msh", ".msh", ".png",
                                                 ".png", ".step", ".step"]  # fmt: skip
    box = json.loads((tmp_path / "part-mesh-box-12-edges.json").read_text())
    assert (box["n_faces"], box["n_structured_faces"], box["open_mesh_edges"]) == (6, 6, 0)
    bracket = json.loads((tmp_path / "part-mesh-l-bracket.json").read_text())
    assert (bracket["n_faces"], bracket["n_structured_faces"]) == (11, 9)
    for report in (box, bracket):
        assert validation_errors(report, "part-mesh-report") == []


def _area(poly):
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


@pytest.mark.parametrize(
    ("uv", "tris", "area"),
    [
        # a flat pair: node 1 halfway along the straight boundary 0-2 (one quad would have
        # a corner of 180 degrees there)
        ([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [1.0, 1.0]], [[0, 1, 3], [1, 2, 3]], 1.0),
        # an arrow-shaped 4-gon (reflex at node 3) split along its outer diagonal 0-2:
        # one triangle inverted, the two overlapping (seen from gmsh in a narrow gap)
        ([[0.0, -1.0], [2.0, 0.0], [0.0, 1.0], [1.0, 0.0]], [[0, 1, 2], [0, 2, 3]], 1.0),
    ],
)
def test_pair_triangles_make_valid_quads(uv, tris, area):
    """Each pair of neighbouring triangles left by a recombination becomes 5 quads that
    tile the pair's 4-gon: every corner turns counter-clockwise (strictly), the areas add
    up to the 4-gon's, and each outer edge is used once."""
    from medax.cad.gmsh_faces import pair_triangles

    uv = np.array(uv)
    new_uv, quads = pair_triangles(np.array(tris), uv, 1.0)
    assert new_uv.shape == (4, 2) and quads.shape == (5, 4)
    allv = np.vstack((uv, new_uv))
    for q in quads:
        p = allv[q]
        e = np.roll(p, -1, axis=0) - p
        b = np.roll(e, 1, axis=0)
        sine = (b[:, 0] * e[:, 1] - b[:, 1] * e[:, 0]) / (
            np.linalg.norm(b, axis=1) * np.linalg.norm(e, axis=1)
        )
        assert sine.min() > 0.05, sine
    assert sum(_area(allv[q]) for q in quads) == pytest.approx(area, rel=1e-12)
    used = [tuple(sorted(e)) for q in quads.tolist() for e in zip(q, q[1:] + q[:1], strict=True)]
    for e in ((0, 1), (1, 2), (2, 3), (0, 3)):  # the 4-gon's sides, once each
        assert used.count(e) == 1


def test_pair_triangles_refuses_lone_triangles():
    from medax.cad.gmsh_faces import pair_triangles

    uv = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [5.0, 5.0], [6.0, 5.0], [5.0, 6.0]])
    assert pair_triangles(np.array([[0, 1, 2], [3, 4, 5]]), uv, 1.0) is None
    assert pair_triangles(np.array([[0, 1, 2]]), uv, 1.0) is None


def test_face_nothing_meshes_gets_finer_edges(monkeypatch):
    """A face that gmsh refuses at the part's counts has its edges divided twice finer (the
    counts propagated), the part is meshed again with the faces whose edges kept their counts
    kept; the result passes the same checks. Refused at every count: the run fails naming
    the face."""
    from medax.cad.gmsh_faces import GmshFaces
    from medax.errors import MeshError

    # (the shaft: doubling its first gmsh face's counts leaves another gmsh face's alone)
    shape, first = _meshed("stepped_shaft")
    topo = build_topology(shape)
    target = first.gmsh_faces[0]
    need = 2 * sum(int(first.edge_counts[j]) for j in topo.face_edges[target])
    real = GmshFaces.mesh
    calls: dict[int, int] = {}

    def picky(self, index):
        calls[index] = calls.get(index, 0) + 1
        n = sum(len(self.nodes.edge_ids[j]) - 1 for j in self.job(index).edges)
        if index == target and n < need:
            raise MeshError(f"face {index}: refused at {n} divisions")
        return real(self, index)

    monkeypatch.setattr(GmshFaces, "mesh", picky)
    m = mesh_part(shape, SIZE)
    for j in topo.face_edges[target]:
        assert m.edge_counts[j] >= 2 * first.edge_counts[j]
    for i in first.gmsh_faces:
        same = all(m.edge_counts[j] == first.edge_counts[j] for j in topo.face_edges[i])
        assert calls[i] == 1 if same else calls[i] in (1, 2)  # (1: after the target)
    assert any(all(m.edge_counts[j] == first.edge_counts[j] for j in topo.face_edges[i])
               for i in first.gmsh_faces)  # fmt: skip
    test_shared_nodes_and_closed((shape, m))
    test_quads_face_outward((shape, m))
    test_nodes_on_their_faces((shape, m))

    need = 10**9
    with pytest.raises(MeshError, match=rf"face {target}: refused .*divided 8 times finer"):
        mesh_part(shape, SIZE)


def test_seam_faces_structured():
    """The stepped shaft's lateral cylinders and torus fillets are 4-sided once the wire's
    two runs along the seam count as sides (circle, seam, circle, seam): each gets the
    structured grid. On a cylinder that is the uniform grid: every node at a radius the
    shaft was built with (10, 15, 8) from the axis, at equal angles and equal heights; each
    mesh edge on the seam is in one quad on each side of it (with the part-wide checks on
    this part: nodes on their faces, shared, closed, no inverted quad)."""
    from medax.cad.face_geometry import surface_type
    from medax.cad.face_region import has_seam

    shape, m = _meshed("stepped_shaft")
    topo = build_topology(shape)
    kinds = {i: surface_type(topo.face(i)) for i in range(topo.n_faces)}
    seamed = {i for i in range(topo.n_faces) if has_seam(topo.face(i))}
    lateral = {i for i, k in kinds.items() if k in ("cylinder", "torus")}
    assert len([i for i in lateral if kinds[i] == "cylinder"]) == 3 and len(lateral) == 5
    assert lateral <= seamed and lateral <= set(m.structured_faces)
    diag = m.diagonal
    for i in (i for i in lateral if kinds[i] == "cylinder"):
        q = m.quads[m.quad_face == i]
        p = m.points[np.unique(q)]
        r = np.hypot(p[:, 0], p[:, 1])
        radius = min((10.0, 15.0, 8.0), key=lambda x: abs(x - r[0]))
        assert np.max(np.abs(r - radius)) < 1e-9 * diag
        heights = np.unique(np.round(p[:, 2] / (1e-9 * diag)))
        a = np.mod(np.arctan2(p[:, 1], p[:, 0]), 2 * np.pi)
        angles = np.unique(np.round(np.where(a > 2 * np.pi - 1e-9, 0.0, a), 9))
        assert len(heights) * len(angles) == len(p)  # a grid of circles x lines
        dz = np.diff(heights) * 1e-9 * diag
        np.testing.assert_allclose(dz, dz[0], atol=1e-8 * diag)
        gaps = np.diff(np.concatenate((angles, [angles[0] + 2 * np.pi])))
        np.testing.assert_allclose(gaps, 2 * np.pi / len(angles), atol=1e-8)
        # every mesh edge of the face is in two of its quads but those on the two circles
        e = np.sort(np.stack((q, np.roll(q, -1, axis=1)), axis=-1).reshape(-1, 2), axis=1)
        _, uses = np.unique(e, axis=0, return_counts=True)
        assert np.count_nonzero(uses == 1) == 2 * len(angles) and uses.max() == 2


@pytest.mark.parametrize("kind", ["cone", "slanted cylinder"])
def test_seam_faces_cone_and_curved_side(kind):
    """A cone frustum's lateral face (its scaled parameters exact in length along the
    circles and the seam only) and a cylinder cut by an inclined plane (a curved side in
    the parameter plane) are structured too: nodes on their faces, shared and closed, no
    inverted quad; on the cylinder every node at radius 10 from the axis."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCone, BRepPrimAPI_MakeCylinder
    from OCP.gp import gp_Ax1, gp_Ax2, gp_Dir, gp_Trsf

    axis = gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1))
    if kind == "cone":
        shape = BRepPrimAPI_MakeCone(axis, 20.0, 8.0, 30.0).Shape()
    else:
        box = BRepPrimAPI_MakeBox(gp_Pnt(-50, -50, 25), 100.0, 100.0, 100.0).Shape()
        turn = gp_Trsf()
        turn.SetRotation(gp_Ax1(gp_Pnt(0, 0, 25), gp_Dir(1, 0, 0)), 0.4)
        cyl = BRepPrimAPI_MakeCylinder(axis, 10.0, 40.0).Shape()
        shape = BRepAlgoAPI_Cut(cyl, BRepBuilderAPI_Transform(box, turn).Shape()).Shape()
    m = mesh_part(shape, 2.0)
    assert len(m.faces) == 3 and m.structured_faces == (0,)  # the lateral face
    test_nodes_on_their_faces((shape, m))
    test_shared_nodes_and_closed((shape, m))
    test_quads_face_outward((shape, m))
    if kind != "cone":
        p = m.points[np.unique(m.quads[m.quad_face == 0])]
        assert np.max(np.abs(np.hypot(p[:, 0], p[:, 1]) - 10.0)) < 1e-9 * m.diagonal


def test_gmsh_session_keeps_sigterm_handler():
    """gmsh's initialisation resets SIGTERM to the default action (the process died at once,
    leaving temporaries, instead of ``medax mesh``'s clean stop); the session puts the
    handler back: a real SIGTERM inside it reaches the handler (in a child process)."""
    import subprocess
    import sys

    code = (
        "import os, signal, sys\n"
        "from medax.mesh.gmsh_session import gmsh_session\n"
        "class Stop(Exception): pass\n"
        "def stop(*_): raise Stop\n"
        "signal.signal(signal.SIGTERM, stop)\n"
        "try:\n"
        "    with gmsh_session():\n"
        "        os.kill(os.getpid(), signal.SIGTERM)\n"
        "        signal.pause()\n"
        "except Stop:\n"
        "    print('stopped cleanly')\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and "stopped cleanly" in r.stdout, (r.returncode, r.stderr)


@pytest.mark.slow
def test_gmsh_worker_survives_hang_and_crash(monkeypatch):
    """A gmsh attempt that hangs (stopped after ``ATTEMPT_TIMEOUT``) or ends the worker
    process counts as failed; a new worker goes on with the next attempt, the other faces
    are served by that same worker, and the part meshes as it did."""
    import os
    import time

    import medax.cad.gmsh_faces as gf

    shape, first = _meshed("plate_with_boss")
    hang, crash = first.gmsh_faces[:2]
    real = gf._mesh

    def flaky(gmsh, path, index, nodes, edges, inner, algorithm, subdivide):
        if (algorithm, subdivide, inner) == gf.ATTEMPTS[0]:
            if index == hang:
                time.sleep(60.0)
            if index == crash:
                os._exit(3)
        return real(gmsh, path, index, nodes, edges, inner, algorithm, subdivide)

    starts = []
    real_start = gf.GmshFaces._start

    def counted(self):
        starts.append(1)
        real_start(self)

    monkeypatch.setattr(gf, "_mesh", flaky)
    # (long enough that an ordinary attempt ends within it on a loaded machine: at a load
    # of 4 - 5, 2 s had stopped ordinary attempts too)
    monkeypatch.setattr(gf, "ATTEMPT_TIMEOUT", 10.0)
    monkeypatch.setattr(gf.GmshFaces, "_start", counted)
    m = mesh_part(shape, SIZE)
    assert len(starts) == 3  # the first worker, one after the hang, one after the crash
    assert {hang, crash} <= set(m.gmsh_faces)
    assert len(m.quads) > 0
    test_shared_nodes_and_closed((shape, m))
    test_quads_face_outward((shape, m))
    test_nodes_on_their_faces((shape, m))


def _u_channel(w=100.0, r=10.0, h=20.0, t=1.0, depth=60.0):
    """A thin U profile (wall ``t``) in the yz plane, legs ``h``, arcs of radius ``r``
    inside and ``r + t`` outside, a bottom ``w`` long, extruded ``depth`` along x: its two
    end faces are thin curved 4-sided strips."""
    from OCP.BRepBuilderAPI import (
        BRepBuilderAPI_MakeEdge,
        BRepBuilderAPI_MakeFace,
        BRepBuilderAPI_MakeWire,
    )
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.GC import GC_MakeArcOfCircle
    from OCP.gp import gp_Vec

    a, b, c = w / 2, w / 2 + r, np.sqrt(0.5)
    wire = BRepBuilderAPI_MakeWire()

    def p(y, z):
        return gp_Pnt(0.0, y, z)

    def line(y0, z0, y1, z1):
        wire.Add(BRepBuilderAPI_MakeEdge(p(y0, z0), p(y1, z1)).Edge())

    def arc(y0, z0, ym, zm, y1, z1):
        wire.Add(BRepBuilderAPI_MakeEdge(GC_MakeArcOfCircle(p(y0, z0), p(ym, zm),
                                                            p(y1, z1)).Value()).Edge())  # fmt: skip

    ro = r + t
    line(-b, r + h, -b, r)
    arc(-b, r, -a - r * c, r - r * c, -a, 0.0)
    line(-a, 0.0, a, 0.0)
    arc(a, 0.0, a + r * c, r - r * c, b, r)
    line(b, r, b, r + h)
    line(b, r + h, b + t, r + h)
    line(b + t, r + h, b + t, r)
    arc(b + t, r, a + ro * c, r - ro * c, a, -t)
    line(a, -t, -a, -t)
    arc(-a, -t, -a - ro * c, r - ro * c, -b - t, r)
    line(-b - t, r, -b - t, r + h)
    line(-b - t, r + h, -b, r + h)
    face = BRepBuilderAPI_MakeFace(wire.Wire()).Face()
    return BRepPrimAPI_MakePrism(face, gp_Vec(depth, 0.0, 0.0)).Shape()


@pytest.mark.slow
def test_thin_curved_strip_structured():
    """The end faces of a thin U channel (1 mm wall): at size 4.1 the inner arcs' own
    counts (4) are below the outer arcs' (6). The chains are evened on the coarsest edges
    (the inner arcs, not the long bottom), so the nodes across the strip stay level and
    every face takes the medial grid with near-rectangular quads."""
    shape = _u_channel()
    m = mesh_part(shape, 4.1)
    assert len(m.structured_faces) == len(m.faces) == 14 and not m.conflicts
    assert quad_quality(m.points, m.quads).scaled_jacobian.min() > 0.95
    test_shared_nodes_and_closed((shape, m))
    test_quads_face_outward((shape, m))
    test_nodes_on_their_faces((shape, m))


def test_counts_even_chains_on_their_coarsest_edges():
    """Opposite chains (20, 17.28, 100, 17.28, 20) and (20, 15.71, 100, 15.71, 20) at size
    4: 6 + 6 + 26 + 6 + 6 against 6 + 4 + 26 + 4 + 6; the two arcs of the short chain (the
    fewest divisions per length) take the 4 missing divisions, edge for edge like the other
    chain."""
    outer = [20.0, 17.28, 100.0, 17.28, 20.0]
    inner = [20.0, 15.71, 100.0, 15.71, 20.0]
    lengths = np.array([1.0, *outer, 1.0, *inner])
    c = division_counts(lengths, range(12), {0: [[0], [1, 2, 3, 4, 5], [6], [11, 10, 9, 8, 7]]},
                        4.0)  # fmt: skip
    assert c.counts[1:6].tolist() == c.counts[7:12].tolist() == [6, 6, 26, 6, 6]
