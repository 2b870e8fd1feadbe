"""The data of the interactive 3D view (``view3d`` JSON, drawn by
[medax.viz.webview][medax.viz.webview]):
a part's faces tessellated coarsely, with what each face is, its edges and fillet axes.

Triangles come from ``BRepMesh_IncrementalMesh`` with a coarse deflection
([VIEW_DEFLECTION][medax.cad.view_data.VIEW_DEFLECTION] x the part's diagonal,
[VIEW_ANGLE][medax.cad.view_data.VIEW_ANGLE] rad): the view is for
looking, and the file stays small (corpus parts: 6 kB for 7 faces, 0.26 MB for 122, 1.5 -
1.9 MB for 1036 and 555 faces). Straight edges are drawn with 2 points, circles with one
per ``ARC_STEP`` rad, other curves with ``EDGE_POINTS``. Arrays are
little-endian float32 / uint32, base64-encoded:

- ``positions``: (n, 3) vertices, each face's vertices contiguous (``faces[i].vertices`` =
  [first, count]); ``indices``: (m, 3) triangles into ``positions``, outward, each face's
  contiguous (``faces[i].triangles`` = [first, count]);
- ``edges`` and ``axes``: (k, 2, 3) line segments (the faces' edges, the fillets' medial
  axes).

Each face has its ``index`` in its solid (``solid``), a ``label`` (its class, or what
simplify made of it), a ``colour`` (RGB 0-1, the pictures' colours), the surface type,
the radius of a blend, its ``neighbours`` (faces sharing an edge) and a ``name`` (the name
the STEP output gives it). ``legend`` lists the labels with colour and count.
"""

from __future__ import annotations

import base64
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.GeomAbs import GeomAbs_Circle, GeomAbs_Line
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS

from medax.cad.simplify.occ import shape_map
from medax.cad.topology import build_topology, edge_points
from medax.cad.xcaf import FaceStyle, class_styles, group_styles
from medax.errors import CadError
from medax.geometry._types import FloatArray

VIEW_DEFLECTION = 4e-3
"""Linear deflection of the view's tessellation, relative to the part's diagonal."""
VIEW_ANGLE = 0.35
"""Angular deflection of the view's tessellation (radians)."""
#: points per edge polyline (ends included): a line gets 2, a circle one per ARC_STEP rad
EDGE_POINTS = 17
ARC_STEP = 0.2
#: points per fillet axis polyline
AXIS_POINTS = 48


def b64(a: np.ndarray, dtype: str) -> str:
    """``a`` as little-endian ``dtype`` bytes, base64 text."""
    return base64.b64encode(
        np.ascontiguousarray(a, dtype=np.dtype(dtype).newbyteorder("<")).tobytes()
    ).decode("ascii")


def face_mesh(face: Any) -> tuple[FloatArray, np.ndarray]:
    """The triangulation of a meshed ``face``: points (n, 3) with its location applied,
    triangles (m, 3) int, outward; empty arrays when it has none."""
    loc = TopLoc_Location()
    tri = BRep_Tool.Triangulation_s(face, loc)
    if tri is None or tri.NbTriangles() == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    trsf = loc.Transformation()
    nodes = (tri.Node(k).Transformed(trsf) for k in range(1, tri.NbNodes() + 1))
    pts = np.array([(p.X(), p.Y(), p.Z()) for p in nodes], dtype=np.float64)
    tris = np.array([tri.Triangle(k).Get() for k in range(1, tri.NbTriangles() + 1)]) - 1
    if face.Orientation() == TopAbs_REVERSED:
        tris = tris[:, ::-1]
    return pts, tris.astype(np.int64)


def _rough_diagonal(shape: Any) -> float:
    """The diagonal of ``shape``'s bounding box as OCCT's quick ``Add`` gives it (enough
    for a deflection; the optimal box costs seconds on large parts)."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box)
    if box.IsVoid():
        return 1.0
    lo, hi = box.CornerMin(), box.CornerMax()
    return float(np.linalg.norm([hi.X() - lo.X(), hi.Y() - lo.Y(), hi.Z() - lo.Z()]))


def _mesh(shape: Any, source: str) -> None:
    """Mesh ``shape`` at the view's deflection, dropping any finer triangulation an earlier
    picture left (BRepMesh keeps one that is fine enough), so the data's size is the same
    with or without pictures."""
    from OCP.BRepTools import BRepTools

    BRepTools.Clean_s(shape)
    try:
        deflection = VIEW_DEFLECTION * _rough_diagonal(shape)
        BRepMesh_IncrementalMesh(shape, deflection, False, VIEW_ANGLE, False)
    except Exception as err:
        raise CadError(f"{source or 'shape'}: meshing for the 3D view failed ({err})") from err


def _edge_segments(shape: Any) -> FloatArray:
    """Segments (k, 2, 3) along every non-degenerate edge of ``shape``."""
    out = []
    for i in range(1, (emap := shape_map(shape, TopAbs_EDGE)).Size() + 1):
        edge = TopoDS.Edge(emap.FindKey(i))
        if BRep_Tool.Degenerated_s(edge):
            continue
        ad = BRepAdaptor_Curve(edge)
        a, b = ad.FirstParameter(), ad.LastParameter()
        kind = ad.GetType()
        if kind == GeomAbs_Line:
            n = 2
        elif kind == GeomAbs_Circle:  # one point per ARC_STEP radians
            n = max(3, int(np.ceil(abs(b - a) / ARC_STEP)) + 1)
        else:
            n = EDGE_POINTS
        pts, _ = edge_points(edge, np.linspace(a, b, n))
        out.append(np.stack([pts[:-1], pts[1:]], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 2, 3))


def _polyline_segments(lines: Sequence[FloatArray]) -> FloatArray:
    segs = [np.stack([p[:-1], p[1:]], axis=1) for p in lines if len(p) > 1]
    return np.concatenate(segs) if segs else np.zeros((0, 2, 3))


def _surface(face: Any) -> str:
    from medax.cad.face_geometry import SURFACE_NAMES

    return SURFACE_NAMES.get(BRepAdaptor_Surface(face).GetType(), "other")


def view_model(
    solids: Sequence[tuple[Any, Sequence[FaceStyle], Sequence[dict[str, Any]]]],
    axes: Sequence[FloatArray] = (),
    title: str = "",
    source: str = "",
) -> dict[str, Any]:
    """The view's data (no header) of solids given as ``(shape, styles, infos)``: styles
    per face in face-map order, and per face a dict with ``label`` and optional
    ``radius``; ``axes``: polylines (k, 3)."""
    positions, indices, faces = [], [], []
    edges = []
    legend: dict[str, dict[str, Any]] = {}
    nv = nt = 0
    for k, (shape, styles, infos) in enumerate(solids):
        _mesh(shape, source)
        topo = build_topology(shape)
        fmap = shape_map(shape, TopAbs_FACE)
        if fmap.Size() != len(styles) or len(infos) != len(styles):
            raise ValueError("one style and one info per face of the solid expected")
        # the styles' order numbers the faces; the topology's maps may order them otherwise
        slot = [fmap.FindIndex(s.face) - 1 for s in styles]
        if sorted(slot) != list(range(len(styles))):
            raise ValueError("the styles are not the faces of the solid, each once")
        index_of = {j: i for i, j in enumerate(slot)}
        for i, (style, info) in enumerate(zip(styles, infos, strict=True)):
            face = TopoDS.Face(style.face)
            pts, tris = face_mesh(face)
            j = slot[i]
            neighbours = sorted(
                {index_of[g] for e in topo.face_edges[j] for g in topo.edge_faces[e] if g != j}
            )
            item: dict[str, Any] = {
                "solid": k,
                "index": i,
                "label": info["label"],
                "name": style.name,
                "colour": [round(float(v), 4) for v in style.rgb],
                "surface": _surface(face),
                "neighbours": neighbours,
                "vertices": [nv, len(pts)],
                "triangles": [nt, len(tris)],
            }
            if info.get("radius") is not None:
                item["radius"] = float(info["radius"])
            faces.append(item)
            positions.append(pts)
            indices.append(tris + nv)
            nv, nt = nv + len(pts), nt + len(tris)
            entry = legend.setdefault(info["label"], {"label": info["label"], "count": 0})
            entry.setdefault("colour", item["colour"])
            entry["count"] += 1
        edges.append(_edge_segments(shape))
    pos = np.concatenate(positions) if positions else np.zeros((0, 3))
    idx = np.concatenate(indices) if indices else np.zeros((0, 3), dtype=np.int64)
    seg = np.concatenate(edges) if edges else np.zeros((0, 2, 3))
    lo = pos.min(axis=0) if len(pos) else np.zeros(3)
    hi = pos.max(axis=0) if len(pos) else np.zeros(3)
    return {
        "title": title,
        "source": source,
        "n_faces": len(faces),
        "n_triangles": int(len(idx)),
        "bounds": [lo.tolist(), hi.tolist()],
        "legend": list(legend.values()),
        "faces": faces,
        "positions": b64(pos, "f4"),
        "indices": b64(idx, "u4"),
        "edges": b64(seg, "f4"),
        "axes": b64(_polyline_segments(axes), "f4"),
    }


def write_view(
    model: dict[str, Any], path: str | Path, unit: str, tolerances: dict[str, float]
) -> None:
    """Write a view as ``view3d`` JSON or as a self-contained HTML page.

    Parameters
    ----------
    model : dict
        The view's data, from [classified_view][medax.cad.view_data.classified_view] or
        [simplified_view][medax.cad.view_data.simplified_view].
    path : str or Path
        The output (the callers pass a staged temporary): ``view3d`` JSON with the header
        (``medax_version``, ``schema_version``, units, tolerances) when it ends in
        ``.json``, else an HTML page with the viewer.
    unit : str
        The length unit of the positions, for the header.
    tolerances : dict of str to float
        The tolerances used, for the header.
    """
    from medax.io_utils import write_json
    from medax.schemas import stamp
    from medax.viz.webview import view_page

    p = Path(path)
    if p.suffix.lower() == ".json":
        write_json(p, stamp("view3d", model, unit, tolerances), "--view3d")
    else:
        label = f"{model['source']}: {model['title']}" if model["source"] else model["title"]
        p.write_text(view_page([(model["title"], model)], label), encoding="utf-8")


def classified_view(solids: Sequence[Any], source: str = "") -> dict[str, Any]:
    """Build the 3D view of classified solids: faces coloured by class, with fillet axes.

    Parameters
    ----------
    solids : sequence of ClassifiedSolid
        The classified solids (``medax.cad.report.ClassifiedSolid``: a classification and
        its fillets' axes).
    source : str
        The file, shown in the view.

    Returns
    -------
    dict
        The view's data without header (see the module's description).

    Raises
    ------
    CadError
        Tessellating a solid fails.
    """
    items = []
    axes: list[FloatArray] = []
    for cs in solids:
        c = cs.classification
        styles = class_styles([c])
        infos = [{"label": f.cls.value, "radius": f.radius} for f in c.faces]
        items.append((c.shape, styles, infos))
        axes.extend(
            a.region.embedding.evaluate(a.spline.sample(AXIS_POINTS)) for a in cs.axes.values()
        )
    return view_model(items, axes, "classified", source)


def simplified_view(
    shapes: Sequence[Any], reports: Sequence[dict[str, Any]], source: str = ""
) -> dict[str, Any]:
    """Build the 3D view of simplified solids, faces coloured by what simplify made of them.

    Merged faces are in their group's colour, kept blends black, untouched faces grey.

    Parameters
    ----------
    shapes : sequence of TopoDS_Shape
        The simplified solids.
    reports : sequence of dict
        Their simplify reports, in the same order.
    source : str
        The file, shown in the view.

    Returns
    -------
    dict
        The view's data without header (see the module's description).

    Raises
    ------
    ValueError
        A report's face groups are not one per face, in order.
    CadError
        Tessellating a solid fails.
    """
    items = []
    for shape, rep in zip(shapes, reports, strict=True):
        groups = rep["face_groups"]
        if [g["new_face"] for g in groups] != list(range(len(groups))):
            raise ValueError("the report's face groups are not one per face, in order")
        styles = group_styles([shape], [rep])
        kept = {b["face"]: b for b in rep["blends_kept"]}
        infos: list[dict[str, Any]] = []
        for g in groups:
            if g["fillet_halves"]:
                infos.append({"label": "merged"})
                continue
            blend = next((kept[i] for i in g["original_faces"] if i in kept), None)
            if blend is not None:
                infos.append({"label": "kept blend", "radius": blend.get("radius")})
            else:
                infos.append({"label": "untouched"})
        items.append((shape, styles, infos))
    model = view_model(items, (), "simplified", source)
    for entry in model["legend"]:
        if entry["label"] == "merged":  # one swatch stands for a colour per merged face
            entry["label"] = "merged, a colour per face"
    return model
