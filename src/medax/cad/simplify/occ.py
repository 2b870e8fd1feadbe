"""Small OCP helpers shared by the simplification modules (maps, sampling, normals).

Points are returned as numpy arrays ``(n, 3)`` in the part's length unit.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.BRepTools import BRepTools
from OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as ShapeMap
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.gp import gp_Pnt
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED, TopAbs_VERTEX
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS

Array = NDArray[np.float64]


def shape_map(shape: Any, kind: Any) -> Any:
    """Indexed map of the sub-shapes of ``kind`` (``TopAbs_FACE``...) of ``shape`` (1-based)."""
    m = ShapeMap()
    TopExp.MapShapes_s(shape, kind, m)
    return m


def compound(shapes: Iterable[Any]) -> Any:
    """A ``TopoDS_Compound`` of ``shapes``."""
    from OCP.BRep import BRep_Builder
    from OCP.TopoDS import TopoDS_Compound

    b = BRep_Builder()
    c = TopoDS_Compound()
    b.MakeCompound(c)
    for s in shapes:
        b.Add(c, s)
    return c


def faces_of(shape: Any) -> Iterator[Any]:
    """Faces of ``shape`` in exploration order (orientation composed)."""
    exp = TopExp_Explorer(shape, TopAbs_FACE)
    while exp.More():
        yield TopoDS.Face(exp.Current())
        exp.Next()


def edges_of(shape: Any) -> Iterator[Any]:
    """Edges of ``shape`` in exploration order, orientation composed with the parent's."""
    exp = TopExp_Explorer(shape, TopAbs_EDGE)
    while exp.More():
        yield TopoDS.Edge(exp.Current())
        exp.Next()


def vertices_of(shape: Any) -> Iterator[Any]:
    """Vertices of ``shape``."""
    exp = TopExp_Explorer(shape, TopAbs_VERTEX)
    while exp.More():
        yield TopoDS.Vertex(exp.Current())
        exp.Next()


def count(shape: Any, kind: Any) -> int:
    """Number of distinct sub-shapes of ``kind``."""
    return int(shape_map(shape, kind).Size())


def xyz(p: Any) -> Array:
    """``gp_Pnt``/``gp_Vec``/``gp_Dir`` -> array (3,)."""
    return np.array([p.X(), p.Y(), p.Z()])


def pnt(a: Array) -> gp_Pnt:
    """``gp_Pnt`` of a point (3,) (the inverse of :func:`xyz`)."""
    return gp_Pnt(float(a[0]), float(a[1]), float(a[2]))


def vertex_point(v: Any) -> Array:
    """Position of a vertex, (3,)."""
    return xyz(BRep_Tool.Pnt_s(v))


def edge_points(edge: Any, n: int) -> Array:
    """``n`` points along an edge (its own parameter, ends included), (n, 3)."""
    c = BRepAdaptor_Curve(edge)
    ts = np.linspace(c.FirstParameter(), c.LastParameter(), n)
    return np.array([xyz(c.Value(float(t))) for t in ts])


def edge_ends(edge: Any) -> tuple[Any, Any]:
    """First and last vertex of an edge following its orientation."""
    return TopExp.FirstVertex_s(edge, True), TopExp.LastVertex_s(edge, True)


def face_normal_at(face: Any, point: Array) -> Array | None:
    """Outward unit normal of ``face`` (orientation applied) at the foot of ``point`` (3,)."""
    surf = BRep_Tool.Surface_s(face)
    proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*map(float, point)), surf)
    if proj.NbPoints() == 0:
        return None
    u, v = proj.LowerDistanceParameters()
    props = BRepLProp_SLProps(BRepAdaptor_Surface(face), u, v, 1, 1e-9)
    if not props.IsNormalDefined():
        return None
    n = xyz(props.Normal())
    if face.Orientation() == TopAbs_REVERSED:
        n = -n
    return n


def max_normal_angle(face1: Any, face2: Any, points: Array) -> float:
    """Largest angle (rad) between the normals of two faces over ``points`` (n, 3).

    ``inf`` when a normal is undefined at a sample. Tangent faces sharing an edge with
    coherent (outward) orientations have angle ~0.
    """
    worst = 0.0
    for p in points:
        n1 = face_normal_at(face1, p)
        n2 = face_normal_at(face2, p)
        if n1 is None or n2 is None:
            return float("inf")
        worst = max(worst, float(np.arccos(np.clip(n1 @ n2, -1.0, 1.0))))
    return worst


def uv_bounds(face: Any) -> tuple[float, float, float, float]:
    """(umin, umax, vmin, vmax) of a face."""
    b = BRepTools.UVBounds_s(face)
    return float(b[0]), float(b[1]), float(b[2]), float(b[3])


def diagonal(shape: Any) -> float:
    """Bounding-box diagonal of ``shape`` (optimal box, no enlargement)."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.AddOptimal_s(shape, box, False, False)
    return float(np.linalg.norm(xyz(box.CornerMax()) - xyz(box.CornerMin())))


def edge_curve(edge: Any) -> tuple[Any, float, float]:
    """(3-D ``Geom_Curve`` with the edge's location applied, first, last) of an edge."""
    first, last = BRep_Tool.Range_s(edge)
    return BRep_Tool.Curve_s(edge, first, last), float(first), float(last)


def face_inside_point(face: Any) -> Array | None:
    """A point inside ``face`` (3,), found on a UV grid with the face classifier."""
    from OCP.gp import gp_Pnt2d
    from OCP.IntTools import IntTools_FClass2d
    from OCP.TopAbs import TopAbs_IN

    cls = IntTools_FClass2d(face, 1e-9)
    u0, u1, v0, v1 = uv_bounds(face)
    surf = BRepAdaptor_Surface(face)
    for fu in (0.5, 0.3, 0.7, 0.1, 0.9, 0.2, 0.8):
        for fv in (0.5, 0.3, 0.7, 0.1, 0.9, 0.2, 0.8):
            u, v = u0 + fu * (u1 - u0), v0 + fv * (v1 - v0)
            if cls.Perform(gp_Pnt2d(u, v)) == TopAbs_IN:
                return xyz(surf.Value(u, v))
    return None


def small_list(shapes: Any) -> list[Any]:
    """Items of a ``List_TopoDS_Shape``. Lists of one or two items (edge -> faces) are read
    with ``First``/``Last``: iterating the binding costs ~0.4 ms per list."""
    n = shapes.Size()
    if n == 0:
        return []
    if n == 1:
        return [shapes.First()]
    if n == 2:
        return [shapes.First(), shapes.Last()]
    return list(shapes)


#: OCCT's default mass properties (``BRepGProp.VolumeProperties_s`` without a tolerance:
#: FreeCAD's, CadQuery's) integrate a face with ``min(2 (degree + 1) x spans in v, 61)``
#: Gauss points along each edge and across the face (``BRepGProp_Face::VIntegrationOrder``),
#: with no split at knots. A merged face carries curvature jumps inside it, where a Gauss
#: rule's error falls as the square of its spacing: the most points read it best.
READER_POINTS = 61


def reader_spans(surf: Any) -> Any:
    """``surf`` (a ``Geom_Surface``), or for a B-spline surface with fewer v spans than
    OCCT's default mass properties need to take their most Gauss points on it
    (:data:`READER_POINTS`), a copy with knots inserted in its largest v spans: the same
    surface to the last bit of its geometry (knot insertion is exact), read by that
    integrator with up to 4x finer points (the 12-fillet box's faces: 1e-4 -> 5e-6 of the
    volume)."""
    from OCP.Geom import Geom_BSplineSurface

    if not isinstance(surf, Geom_BSplineSurface):
        return surf
    need = -(-READER_POINTS // (2 * (surf.VDegree() + 1)))
    if surf.NbVKnots() - 1 >= need:
        return surf
    out = surf.Copy()
    knots = np.array([out.VKnot(j) for j in range(1, out.NbVKnots() + 1)])
    gaps = np.diff(knots)
    # each span cut into equal parts, the largest spans into the most, ``need`` in all
    parts = np.maximum(1, np.floor(need * gaps / gaps.sum()).astype(int))
    while parts.sum() < need:
        parts[np.argmax(gaps / parts)] += 1
    for a, b, n in zip(knots[:-1], knots[1:], parts, strict=True):
        for t in a + (b - a) * np.arange(1, n) / n:
            out.InsertVKnot(float(t), 1, 0.0, True)
    return out


def knot_arrays(t: Array) -> tuple[Any, Any]:
    """OCCT's distinct knots and multiplicities (``TColStd_Array1OfReal``,
    ``TColStd_Array1OfInteger``) of a full knot vector ``t`` (n,)."""
    from OCP.collections import Array1_double, Array1_int

    u, m = np.unique(np.asarray(t, dtype=np.float64), return_counts=True)
    ak, am = Array1_double(1, len(u)), Array1_int(1, len(u))
    for k, (kv, mult) in enumerate(zip(u, m, strict=True)):
        ak.SetValue(k + 1, float(kv))
        am.SetValue(k + 1, int(mult))
    return ak, am


def bspline_surface(poles: Array, tu: Array, tv: Array, udeg: int, vdeg: int) -> Any:
    """The polynomial ``Geom_BSplineSurface`` of ``poles`` (nu, nv, 3) on the full knot
    vectors ``tu``, ``tv`` (with repeats) of degrees ``udeg``, ``vdeg``."""
    from OCP.collections import Array2_gp_Pnt
    from OCP.Geom import Geom_BSplineSurface

    nu, nv = poles.shape[:2]
    out = Array2_gp_Pnt(1, nu, 1, nv)
    for i, row in enumerate(np.asarray(poles, dtype=np.float64).tolist(), start=1):
        for j, (x, y, z) in enumerate(row, start=1):  # (Python floats: one call a pole)
            out.SetValue(i, j, gp_Pnt(x, y, z))
    (uk, um), (vk, vm) = knot_arrays(tu), knot_arrays(tv)
    return Geom_BSplineSurface(out, uk, vk, um, vm, udeg, vdeg)
