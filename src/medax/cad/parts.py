"""Filleted test parts built with OCCT at run time, with the fillet builder's truth.

Each builder returns a :class:`BuiltPart`: the solid and the faces the fillet builder made
(``BRepFilletAPI_MakeFillet.Generated`` of every filleted edge and of every vertex, i.e.
edge blends and corner blends). Lengths in mm. Used by the tests, the demo and the
benchmark; nothing here reads a file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse
from OCP.BRepBuilderAPI import (
    BRepBuilderAPI_MakeEdge,
    BRepBuilderAPI_MakeFace,
    BRepBuilderAPI_MakePolygon,
    BRepBuilderAPI_MakeWire,
)
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCylinder, BRepPrimAPI_MakePrism
from OCP.GC import GC_MakeArcOfCircle
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt, gp_Vec
from OCP.TopAbs import TopAbs_SOLID, TopAbs_VERTEX
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS

from medax.cad.topology import build_topology, edge_params, edge_points
from medax.errors import CadError


@dataclass(frozen=True)
class BuiltPart:
    """A solid and the blend faces its fillet builder(s) generated (``TopoDS_Face`` list).

    ``radii``: the constant radii used (empty for a variable-radius blend)."""

    name: str
    shape: Any
    blends: tuple[Any, ...]
    radii: tuple[float, ...]

    @property
    def radius(self) -> float:
        """The (first) constant radius."""
        return self.radii[0]


def _solid(shape: Any) -> Any:
    exp = TopExp_Explorer(shape, TopAbs_SOLID)
    if not exp.More():
        raise CadError("part builder produced no solid")
    return TopoDS.Solid(exp.Current())


def fillet(
    shape: Any,
    edges: list[Any],
    radius: float | tuple[float, float],
    name: str,
    previous: BuiltPart | None = None,
) -> BuiltPart:
    """Fillet ``edges`` of ``shape`` with ``radius`` (or a linear law ``(r1, r2)``); record
    the generated blend faces, plus ``previous``'s blends carried through this operation."""
    mk = BRepFilletAPI_MakeFillet(shape)
    for e in edges:
        if isinstance(radius, tuple):
            mk.Add(radius[0], radius[1], e)
        else:
            mk.Add(radius, e)
    mk.Build()
    if not mk.IsDone():
        raise CadError(f"{name}: OCCT could not fillet {len(edges)} edges with r={radius}")
    out = mk.Shape()
    blends: list[Any] = []
    sources = list(edges)
    exp = TopExp_Explorer(shape, TopAbs_VERTEX)
    while exp.More():
        sources.append(exp.Current())
        exp.Next()
    for s in sources:
        for f in mk.Generated(s):
            if not any(f.IsSame(b) for b in blends):
                blends.append(f)
    radii: tuple[float, ...] = () if isinstance(radius, tuple) else (float(radius),)
    if previous is not None:
        radii = tuple(sorted(set(radii + previous.radii)))
        for f in previous.blends:
            mod = list(mk.Modified(f))
            blends.extend(mod if mod else [] if mk.IsDeleted(f) else [f])
    solid = _solid(out)
    if not BRepCheck_Analyzer(solid).IsValid():
        raise CadError(f"{name}: the filleted solid is not valid")
    return BuiltPart(name, solid, tuple(TopoDS.Face(f) for f in blends), radii)


def _edges(shape: Any) -> list[Any]:
    topo = build_topology(shape)
    return [topo.edge(j) for j in range(topo.n_edges)]


def _edge_mid(e: Any) -> np.ndarray:
    p, _ = edge_points(e, edge_params(e, 1))
    return p[0]


def _select(shape: Any, pred: Any) -> list[Any]:
    return [e for e in _edges(shape) if pred(_edge_mid(e))]


def box_random(seed: int, radius: float = 2.0) -> BuiltPart:
    """A 30 x 20 x 10 box with a random subset of its 12 edges filleted (corner blends
    appear where three filleted edges meet)."""
    rng = np.random.default_rng(seed)
    box = BRepPrimAPI_MakeBox(30.0, 20.0, 10.0).Shape()
    edges = _edges(box)
    k = int(rng.integers(1, 13))
    pick = sorted(rng.choice(12, size=k, replace=False).tolist())
    return fillet(box, [edges[j] for j in pick], radius, f"box_random_{seed}")


def _prism(points: list[tuple[float, float]], height: float) -> Any:
    poly = BRepBuilderAPI_MakePolygon()
    for x, y in points:
        poly.Add(gp_Pnt(x, y, 0.0))
    poly.Close()
    face = BRepBuilderAPI_MakeFace(poly.Wire()).Face()
    return BRepPrimAPI_MakePrism(face, gp_Vec(0.0, 0.0, height)).Shape()


def l_bracket(radius: float = 3.0) -> BuiltPart:
    """An L-bracket (40 x 30, 8 thick, 25 deep) with a through hole in one leg; the inner
    (concave) and outer corner edges filleted."""
    pts = [(0.0, 0.0), (40.0, 0.0), (40.0, 8.0), (8.0, 8.0), (8.0, 30.0), (0.0, 30.0)]
    body = _prism(pts, 25.0)
    hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(25.0, -1.0, 12.5), gp_Dir(0, 1, 0)), 4.0, 10.0)
    body = BRepAlgoAPI_Cut(body, hole.Shape()).Shape()
    edges = _select(
        body,
        lambda m: (
            (abs(m[0] - 8.0) < 1e-6 and abs(m[1] - 8.0) < 1e-6)
            or (abs(m[0]) < 1e-6 and abs(m[1]) < 1e-6)
        ),
    )
    return fillet(_solid(body), edges, radius, "l_bracket")


def plate_with_boss(radius: float = 2.0) -> BuiltPart:
    """A 60 x 40 x 6 plate with a cylindrical boss (r = 8, 10 high) and a hole through it;
    the boss root (concave, a torus) and top (convex) edges filleted."""
    plate = BRepPrimAPI_MakeBox(60.0, 40.0, 6.0).Shape()
    boss = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(30.0, 20.0, 6.0), gp_Dir(0, 0, 1)), 8.0, 10.0)
    body = BRepAlgoAPI_Fuse(plate, boss.Shape()).Shape()
    hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(30.0, 20.0, -1.0), gp_Dir(0, 0, 1)), 3.0, 20.0)
    body = BRepAlgoAPI_Cut(body, hole.Shape()).Shape()

    def on_boss_circle(m: np.ndarray) -> bool:
        r = float(np.hypot(m[0] - 30.0, m[1] - 20.0))
        return abs(r - 8.0) < 1e-6 and (abs(m[2] - 6.0) < 1e-6 or abs(m[2] - 16.0) < 1e-6)

    return fillet(_solid(body), _select(body, on_boss_circle), radius, "plate_with_boss")


def stepped_shaft(radius: float = 1.5) -> BuiltPart:
    """A shaft of three diameters (20, 30, 16) along z; both shoulder roots filleted."""
    a = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 10.0, 30.0).Shape()
    b = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 30), gp_Dir(0, 0, 1)), 15.0, 20.0).Shape()
    c = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 50), gp_Dir(0, 0, 1)), 8.0, 25.0).Shape()
    body = BRepAlgoAPI_Fuse(BRepAlgoAPI_Fuse(a, b).Shape(), c).Shape()

    def root(m: np.ndarray) -> bool:
        r = float(np.hypot(m[0], m[1]))
        return (abs(m[2] - 30.0) < 1e-6 and abs(r - 10.0) < 1e-6) or (
            abs(m[2] - 50.0) < 1e-6 and abs(r - 8.0) < 1e-6
        )

    return fillet(_solid(body), _select(body, root), radius, "stepped_shaft")


def pocket(radius: float = 4.0) -> BuiltPart:
    """A 60 x 40 x 15 block with a 30 x 20 x 8 pocket; its 4 vertical corners filleted."""
    block = BRepPrimAPI_MakeBox(60.0, 40.0, 15.0).Shape()
    cut = BRepPrimAPI_MakeBox(gp_Pnt(15.0, 10.0, 7.0), 30.0, 20.0, 10.0).Shape()
    body = BRepAlgoAPI_Cut(block, cut).Shape()
    xs, ys = (15.0, 45.0), (10.0, 30.0)
    edges = _select(
        body,
        lambda m: (
            any(abs(m[0] - x) < 1e-6 for x in xs)
            and any(abs(m[1] - y) < 1e-6 for y in ys)
            and 7.0 < m[2] < 15.0
        ),
    )
    return fillet(_solid(body), edges, radius, "pocket")


def slotted_plate(radius: float = 1.0) -> BuiltPart:
    """A 60 x 30 x 8 plate with a through slot (width 10, rounded ends: the slot trap);
    the plate's four vertical outer edges filleted (true blends next to the trap)."""
    plate = BRepPrimAPI_MakeBox(60.0, 30.0, 8.0).Shape()
    slot = _obround(20.0, 40.0, 15.0, 5.0, -1.0, 10.0)
    body = BRepAlgoAPI_Cut(plate, slot).Shape()
    edges = _select(
        body,
        lambda m: (
            (abs(m[0]) < 1e-6 or abs(m[0] - 60.0) < 1e-6)
            and (abs(m[1]) < 1e-6 or abs(m[1] - 30.0) < 1e-6)
        ),
    )
    return fillet(_solid(body), edges, radius, "slotted_plate")


def _obround(x0: float, x1: float, yc: float, r: float, z0: float, h: float) -> Any:
    """A stadium prism: straight from x0 to x1 at y = yc +- r, half-circle ends."""
    p = [gp_Pnt(x0, yc - r, z0), gp_Pnt(x1, yc - r, z0), gp_Pnt(x1, yc + r, z0)]
    q = [gp_Pnt(x0, yc + r, z0), gp_Pnt(x0, yc - r, z0)]
    w = BRepBuilderAPI_MakeWire()
    w.Add(BRepBuilderAPI_MakeEdge(p[0], p[1]).Edge())
    arc1 = GC_MakeArcOfCircle(p[1], gp_Pnt(x1 + r, yc, z0), p[2]).Value()
    w.Add(BRepBuilderAPI_MakeEdge(arc1).Edge())
    w.Add(BRepBuilderAPI_MakeEdge(p[2], q[0]).Edge())
    arc2 = GC_MakeArcOfCircle(q[0], gp_Pnt(x0 - r, yc, z0), q[1]).Value()
    w.Add(BRepBuilderAPI_MakeEdge(arc2).Edge())
    face = BRepBuilderAPI_MakeFace(w.Wire()).Face()
    return BRepPrimAPI_MakePrism(face, gp_Vec(0.0, 0.0, h)).Shape()


def boss_grid(n: int = 8, radius: float = 1.0) -> BuiltPart:
    """A plate with an ``n x n`` grid of round bosses, every boss root and top edge
    filleted: ``4 n^2 + 6`` faces or so (n = 12 gives over 500), for benchmarks."""
    pitch = 10.0
    size = n * pitch
    body = BRepPrimAPI_MakeBox(size, size, 4.0).Shape()
    fuse_tools = []
    for a in range(n):
        for b in range(n):
            c = gp_Pnt(pitch * (a + 0.5), pitch * (b + 0.5), 4.0)
            fuse_tools.append(
                BRepPrimAPI_MakeCylinder(gp_Ax2(c, gp_Dir(0, 0, 1)), 3.0, 5.0).Shape()
            )
    from OCP.collections import List_TopoDS_Shape as TopTools_ListOfShape

    args, tools = TopTools_ListOfShape(), TopTools_ListOfShape()
    args.Append(body)
    for t in fuse_tools:
        tools.Append(t)
    fuse = BRepAlgoAPI_Fuse()
    fuse.SetArguments(args)
    fuse.SetTools(tools)
    fuse.Build()
    body = fuse.Shape()

    def boss_edge(m: np.ndarray) -> bool:
        du = (m[0] % pitch) - 0.5 * pitch
        dv = (m[1] % pitch) - 0.5 * pitch
        return abs(np.hypot(du, dv) - 3.0) < 1e-6 and m[2] > 3.9

    return fillet(_solid(body), _select(body, boss_edge), radius, f"boss_grid_{n}")


def variable_radius_box() -> BuiltPart:
    """A box with one edge filleted by a radius growing linearly from 1 to 3 (a B-spline
    blend surface)."""
    box = BRepPrimAPI_MakeBox(30.0, 20.0, 10.0).Shape()
    return fillet(box, [_edges(box)[0]], (1.0, 3.0), "variable_radius_box")


def rounded_box_chain() -> BuiltPart:
    """A box with its vertical edges rounded (r = 4), then its top loop of 8 tangent edges
    filleted (r = 1.5): a chain of cylinders and tori meeting tangentially at cross edges."""
    box = BRepPrimAPI_MakeBox(30.0, 20.0, 10.0).Shape()
    vertical = fillet(box, _select(box, lambda m: abs(m[2] - 5.0) < 1e-6), 4.0, "vertical")
    top = _select(vertical.shape, lambda m: abs(m[2] - 10.0) < 1e-6)
    return fillet(vertical.shape, top, 1.5, "rounded_box_chain", previous=vertical)


def slanted_boss(radius: float = 2.0) -> BuiltPart:
    """A plate with a slanted cylinder through it; the root fillet is a B-spline
    rolling-ball surface."""
    plate = BRepPrimAPI_MakeBox(60.0, 60.0, 5.0).Shape()
    axis = gp_Ax2(gp_Pnt(30.0, 30.0, -5.0), gp_Dir(0.3, 0.0, 1.0))
    body = BRepAlgoAPI_Fuse(plate, BRepPrimAPI_MakeCylinder(axis, 8.0, 25.0).Shape()).Shape()

    def root(m: np.ndarray) -> bool:
        return abs(m[2] - 5.0) < 1e-6 and 1.0 < m[0] < 59.0 and 1.0 < m[1] < 59.0

    return fillet(_solid(body), _select(body, root), radius, "slanted_boss")


def slanted_hole(radius: float = 1.5) -> BuiltPart:
    """A plate with a slanted cylindrical hole through it, both rims filleted: two B-spline
    rolling-ball blends on the one cylinder face, their contact curves in parallel planes."""
    plate = BRepPrimAPI_MakeBox(60.0, 60.0, 5.0).Shape()
    axis = gp_Ax2(gp_Pnt(30.0, 30.0, -5.0), gp_Dir(0.3, 0.0, 1.0))
    body = BRepAlgoAPI_Cut(plate, BRepPrimAPI_MakeCylinder(axis, 8.0, 25.0).Shape()).Shape()

    def rim(m: np.ndarray) -> bool:
        return 10.0 < m[0] < 50.0 and 10.0 < m[1] < 50.0

    return fillet(_solid(body), _select(body, rim), radius, "slanted_hole")


def oblique_end_fillet(radius: float = 2.0) -> BuiltPart:
    """A prism on the quadrilateral (0, 0), (30, 0), (25, 20), (0, 20), 10 high, its top
    front edge filleted: the fillet runs into the oblique end face, so its two smooth edges
    end 0.5 apart along it (7 faces, one cylinder blend)."""
    body = _prism([(0.0, 0.0), (30.0, 0.0), (25.0, 20.0), (0.0, 20.0)], 10.0)

    def top_front(m: np.ndarray) -> bool:
        return abs(m[1]) < 1e-9 and abs(m[2] - 10.0) < 1e-9

    return fillet(_solid(body), _select(body, top_front), radius, "oblique_end_fillet")


def block_on_cylinder(radius: float = 2.0) -> BuiltPart:
    """A cylinder (r = 20, 30 high, its seam at +x) with a 25 x 10 x 10 block fused onto
    its side across the seam, the block's four edges that run out from the wall filleted:
    each fillet ends on the cylinder's face, which the simplification rebuilds on its own
    surface (12 faces, four cylinder blends)."""
    cyl = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 20.0, 30.0)
    block = BRepPrimAPI_MakeBox(gp_Pnt(15.0, -5.0, 10.0), 25.0, 10.0, 10.0).Shape()
    body = BRepAlgoAPI_Fuse(cyl.Shape(), block).Shape()

    def runs_out(m: np.ndarray) -> bool:
        return 21.0 < m[0] < 39.0 and abs(abs(m[1]) - 5.0) < 1e-6 and abs(m[2] - 15.0) > 4.0

    return fillet(_solid(body), _select(body, runs_out), radius, "block_on_cylinder")


def tilted_cylinder(
    direction: tuple[float, float, float] = (0.5, 0.0, 0.866025403784329), radius: float = 3.0
) -> BuiltPart:
    """A cylinder (r = 38.75, 20 long) along a tilted axis, its top edge filleted: a
    quarter torus all the way round (as on ANC101's tilted boss, whose torus's v = 0 circle
    projects partly onto v = 2 pi)."""
    ax = np.asarray(direction, dtype=np.float64)
    ax /= np.linalg.norm(ax)
    base = gp_Ax2(gp_Pnt(304.375, 100.25, 169.67), gp_Dir(*map(float, ax)))
    cyl = BRepPrimAPI_MakeCylinder(base, 38.75, 20.0).Shape()
    top = max(_edges(cyl), key=lambda e: float(_edge_mid(e) @ ax))
    return fillet(_solid(cyl), [top], radius, "tilted_cylinder")


#: the catalogue used by tests and the demo (name -> builder without arguments)
CATALOGUE = {
    "l_bracket": l_bracket,
    "plate_with_boss": plate_with_boss,
    "stepped_shaft": stepped_shaft,
    "pocket": pocket,
    "slotted_plate": slotted_plate,
    "variable_radius_box": variable_radius_box,
    "rounded_box_chain": rounded_box_chain,
    "slanted_boss": slanted_boss,
}

__all__ = ["CATALOGUE", "BuiltPart", "box_random", "boss_grid", "fillet"]
