"""Filleted test parts built with OCCT, with the blend faces known from the fillet history.

Used by the tests, the demo and the benchmark (no files needed). Every builder returns a
:class:`BuiltPart`: the solid and the 0-based indices (in ``shape_map(shape, FACE)`` order)
of the faces the fillet builder generated.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder
from OCP.collections import List_TopoDS_Shape
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
from OCP.TopoDS import TopoDS

from medax.cad.simplify.occ import edge_points, shape_map, vertex_point
from medax.errors import CadError


@dataclass(frozen=True)
class BuiltPart:
    """A filleted solid and the indices of its blend faces (from the fillet history)."""

    name: str
    shape: Any
    blends: tuple[int, ...]


def fillet(shape: Any, edges: Iterable[Any], radius: float, name: str) -> BuiltPart:
    """Fillet ``edges`` of ``shape`` with ``radius``; blend faces from ``Generated``."""
    mk = BRepFilletAPI_MakeFillet(shape)
    edges = list(edges)
    for e in edges:
        mk.Add(radius, e)
    mk.Build()
    if not mk.IsDone():
        raise CadError(f"{name}: the fillet builder failed (radius {radius})")
    result = mk.Shape()
    fmap = shape_map(result, TopAbs_FACE)
    blends: set[int] = set()
    sources = list(edges) + [
        shape_map(shape, TopAbs_VERTEX).FindKey(i)
        for i in range(1, shape_map(shape, TopAbs_VERTEX).Size() + 1)
    ]
    for s in sources:
        for g in mk.Generated(s):
            i = fmap.FindIndex(g)
            if i > 0:
                blends.add(i - 1)
    return BuiltPart(name, result, tuple(sorted(blends)))


def unify(shape: Any) -> Any:
    """Merge faces and edges lying on the same surface/curve (after booleans)."""
    from OCP.ShapeUpgrade import ShapeUpgrade_UnifySameDomain

    u = ShapeUpgrade_UnifySameDomain(shape, True, True, False)
    u.Build()
    return u.Shape()


def _edges_where(shape: Any, pred: Any) -> list[Any]:
    emap = shape_map(shape, TopAbs_EDGE)
    out = []
    for i in range(1, emap.Size() + 1):
        e = TopoDS.Edge(emap.FindKey(i))
        if pred(edge_points(e, 3)):
            out.append(e)
    return out


def box_vertical_fillets(a: float = 40.0, b: float = 30.0, h: float = 20.0, r: float = 5.0):
    """Box ``a x b x h`` with its 4 vertical edges filleted (10 faces, 4 cylinders)."""
    box = BRepPrimAPI_MakeBox(a, b, h).Shape()
    edges = _edges_where(box, lambda p: abs(p[0, 2] - p[-1, 2]) > 1e-9)
    return fillet(box, edges, r, "box with 4 filleted vertical edges")


def box_all_fillets(a: float = 40.0, b: float = 30.0, h: float = 20.0, r: float = 4.0):
    """Box with all 12 edges filleted (26 faces: 12 cylinders, 8 sphere corners)."""
    box = BRepPrimAPI_MakeBox(a, b, h).Shape()
    return fillet(box, _edges_where(box, lambda p: True), r, "box with 12 filleted edges")


def pocket_fillets(
    a: float = 60.0, b: float = 50.0, h: float = 20.0, depth: float = 12.0, r: float = 3.0
) -> BuiltPart:
    """Block ``a x b x h`` with a pocket ``(a - 20) x (b - 20)`` and ``depth`` deep cut into its
    top, the pocket's 4 floor and 4 vertical edges filleted (concave: 8 cylinders and 4
    sphere corners; 23 faces). Mirrored across the top, the pocket is a box
    ``(a - 20) x (b - 20) x 2 depth`` with all edges rounded: its volume is half of that."""
    from OCP.gp import gp_Pnt as _P

    block = BRepPrimAPI_MakeBox(a, b, h).Shape()
    pocket = BRepPrimAPI_MakeBox(_P(10.0, 10.0, h - depth), a - 20.0, b - 20.0, depth + 1.0)
    shape = unify(BRepAlgoAPI_Cut(block, pocket.Shape()).Shape())

    def inner(p: Any) -> bool:
        import numpy as np

        x, y, z = p[:, 0], p[:, 1], p[:, 2]
        eps = 1e-9
        inside = (x > 10 - eps) & (x < a - 10 + eps) & (y > 10 - eps) & (y < b - 10 + eps)
        return bool(np.all(inside) and not np.all(z > h - eps))

    return fillet(shape, _edges_where(shape, inner), r, "block with a filleted pocket")


def plate_with_boss(r: float = 3.0, hole: bool = True) -> BuiltPart:
    """Plate 80x60x10 with a boss (radius 12, height 15) whose root edge is filleted.

    With ``hole`` a through hole (radius 5) off the boss axis: 10 faces, one torus blend.
    """
    plate = BRepPrimAPI_MakeBox(80.0, 60.0, 10.0).Shape()
    boss = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(30, 30, 0), gp_Dir(0, 0, 1)), 12.0, 25.0)
    shape = BRepAlgoAPI_Fuse(plate, boss.Shape()).Shape()
    if hole:
        drill = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(65, 15, -1), gp_Dir(0, 0, 1)), 5.0, 12.0)
        shape = BRepAlgoAPI_Cut(shape, drill.Shape()).Shape()
    shape = unify(shape)

    def root(p: Any) -> bool:
        import numpy as np

        d = np.hypot(p[:, 0] - 30, p[:, 1] - 30)
        return bool(np.all(np.abs(p[:, 2] - 10) < 1e-7) and np.all(np.abs(d - 12) < 1e-6))

    return fillet(shape, _edges_where(shape, root), r, "plate with filleted boss")


def grid_plate(n: int = 8, m: int = 8, r: float = 1.0) -> BuiltPart:
    """Plate with ``n x m`` filleted square bosses (straight-edge fillets, many faces).

    Each boss is a 6x6x4 block whose 4 vertical edges are filleted (radius ``r``); the
    plate's own 4 vertical edges too. ``n = m = 8`` gives 389 faces, 10 x 10 gives 605.
    """
    pitch = 10.0
    plate = BRepPrimAPI_MakeBox(n * pitch + 4, m * pitch + 4, 3.0).Shape()
    shape = plate
    tools = []
    for i in range(n):
        for j in range(m):
            blk = BRepPrimAPI_MakeBox(gp_Pnt(4 + i * pitch, 4 + j * pitch, 3.0), 6.0, 6.0, 4.0)
            tools.append(blk.Shape())
    args = List_TopoDS_Shape()
    args.Append(plate)
    tl = List_TopoDS_Shape()
    for t in tools:
        tl.Append(t)
    fuse = BRepAlgoAPI_Fuse()
    fuse.SetArguments(args)
    fuse.SetTools(tl)
    fuse.Build()
    shape = fuse.Shape()
    shape = unify(shape)

    def vertical_boss_or_outer(p: Any) -> bool:
        return bool(abs(p[0, 2] - p[-1, 2]) > 1e-9 and abs(p[0, 0] - p[-1, 0]) < 1e-9)

    return fillet(shape, _edges_where(shape, vertical_boss_or_outer), r, "grid plate")


def vertex_positions(shape: Any) -> list[Any]:
    """All vertex positions of ``shape`` (for debugging)."""
    vmap = shape_map(shape, TopAbs_VERTEX)
    return [vertex_point(TopoDS.Vertex(vmap.FindKey(i))) for i in range(1, vmap.Size() + 1)]


def boss_top_fillet(r: float = 2.0, root: bool = True) -> BuiltPart:
    """Plate 80x60x10 with a boss (radius 12, top at z = 25) whose top edge is filleted
    (the boss top disk then merges on a revolution surface through the axis); with ``root``
    its root edge too. 9 faces (10 with ``root``)."""
    plate = BRepPrimAPI_MakeBox(80.0, 60.0, 10.0).Shape()
    boss = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(30, 30, 0), gp_Dir(0, 0, 1)), 12.0, 25.0)
    shape = unify(BRepAlgoAPI_Fuse(plate, boss.Shape()).Shape())

    def circle_at(z: float) -> Any:
        def pred(p: Any) -> bool:
            import numpy as np

            d = np.hypot(p[:, 0] - 30, p[:, 1] - 30)
            return bool(np.all(np.abs(p[:, 2] - z) < 1e-7) and np.all(np.abs(d - 12) < 1e-6))

        return pred

    edges = _edges_where(shape, circle_at(25.0))
    if root:
        edges += _edges_where(shape, circle_at(10.0))
    return fillet(shape, edges, r, "plate with boss, top edge filleted")
