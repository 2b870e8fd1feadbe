"""Build the new faces on shared edges and assemble the simplified solid.

Every run of a group's boundary becomes one edge, shared by the two faces it separates: an
original edge when the run has one edge, else the run's curves joined into one B-spline
(``GeomConvert_CompCurveToBSplineCurve``) between the run's end vertices. Faces are built on
their (new or original) surface with pcurves projected explicitly, then healed
(``ShapeFix_Shape``) and made same-parameter.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
from OCP.BRepLib import BRepLib
from OCP.Geom import Geom_TrimmedCurve
from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
from OCP.GeomConvert import GeomConvert, GeomConvert_CompCurveToBSplineCurve
from OCP.GeomProjLib import GeomProjLib
from OCP.gp import gp_Pnt
from OCP.ShapeFix import ShapeFix_Shape
from OCP.TopAbs import TopAbs_REVERSED
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shell, TopoDS_Solid, TopoDS_Wire

from medax.cad.simplify.groups import Group, Run
from medax.cad.simplify.occ import (
    edge_curve,
    edge_ends,
    edge_points,
    edges_of,
    face_inside_point,
    face_normal_at,
    xyz,
)
from medax.cad.simplify.split import SplitResult
from medax.errors import CadError

log = logging.getLogger(__name__)


def _joined_edge(run: Run, tol: float) -> Any:
    comp = None
    for e in run.edges:
        c, f, l = edge_curve(e)
        tc = Geom_TrimmedCurve(c, f, l)
        if e.Orientation() == TopAbs_REVERSED:
            tc.Reverse()
        bs = GeomConvert.CurveToBSplineCurve_s(tc)
        if comp is None:
            comp = GeomConvert_CompCurveToBSplineCurve(bs)
        elif not comp.Add(bs, tol, True):
            raise CadError("boundary edges of a merged face do not join into one curve")
    assert comp is not None
    curve = comp.BSplineCurve()
    v0 = edge_ends(run.edges[0])[0]
    v1 = edge_ends(run.edges[-1])[1]
    mk = BRepBuilderAPI_MakeEdge(curve, v0, v1)
    if not mk.IsDone():
        raise CadError("could not build a joined boundary edge")
    return mk.Edge()


def _surface_normal(surf: Any, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*map(float, p)), surf)
    u, v = proj.LowerDistanceParameters()
    d1u, d1v = surf.DN(u, v, 1, 0), surf.DN(u, v, 0, 1)
    n = np.cross(xyz(d1u), xyz(d1v))
    return n / np.linalg.norm(n), xyz(proj.NearestPoint())


def _add_pcurves(face: Any, surf: Any, tol: float) -> None:
    builder = BRep_Builder()
    for e in edges_of(face):
        c, f, l = edge_curve(e)
        pc = GeomProjLib.Curve2d_s(c, f, l, surf, tol)
        if pc is None:
            raise CadError("projecting a boundary edge onto a new surface failed")
        builder.UpdateEdge(TopoDS.Edge(e), pc, face, tol)


def build_solid(
    split: SplitResult, groups: list[Group], surfaces: dict[int, Any], tol: float
) -> tuple[Any, list[Any]]:
    """The simplified solid and the new face of each group (same order as ``groups``).

    ``surfaces`` maps a supporting face (original index) to its merged ``Geom_Surface``.
    """
    builder = BRep_Builder()
    joined: dict[frozenset[int], tuple[Any, int]] = {}
    faces: list[Any] = []
    for g in groups:
        member = TopoDS.Face(split.face_map.FindKey(g.members[0] + 1))
        if g.untouched:
            faces.append(member)
            continue
        if g.support is not None:
            surf = surfaces[g.support]
            ref = next(
                TopoDS.Face(split.face_map.FindKey(k + 1))
                for k in g.members
                if split.origin[k] == g.support
            )
            p = face_inside_point(ref)
            if p is None:  # a boundary point serves too: the surfaces are smooth there
                p = edge_points(next(edges_of(ref)), 3)[1]
            n_out = face_normal_at(ref, p)
            n_new, _ = _surface_normal(surf, p)
            flip = n_out is None or float(n_out @ n_new) < 0
        else:  # the face's own surface: its orientation says it all
            surf = BRep_Tool.Surface_s(member)
            flip = member.Orientation() == TopAbs_REVERSED
        face = TopoDS_Face()
        builder.MakeFace(face, surf, tol)
        for loop in g.loops:
            edges: list[Any] = []
            for run in loop:
                if len(run.edges) == 1:
                    edges.append(run.edges[0])
                    continue
                key = frozenset(run.indices)
                if key not in joined:
                    joined[key] = (_joined_edge(run, tol), g.id)
                edge, owner = joined[key]
                edges.append(edge if owner == g.id else edge.Reversed())
            if flip:
                edges = [e.Reversed() for e in reversed(edges)]
            wire = TopoDS_Wire()
            builder.MakeWire(wire)
            for e in edges:
                builder.Add(wire, e)
            wire.Closed(True)
            builder.Add(face, wire)
        _add_pcurves(face, surf, tol)
        if flip:
            face.Reverse()
        faces.append(face)
    shell = TopoDS_Shell()
    builder.MakeShell(shell)
    for f in faces:
        builder.Add(shell, f)
    shell.Closed(True)
    solid = TopoDS_Solid()
    builder.MakeSolid(solid)
    builder.Add(solid, shell)
    fix = ShapeFix_Shape(solid)
    fix.SetPrecision(tol)
    fix.SetMaxTolerance(1e3 * tol)
    fix.Perform()
    result = fix.Shape()
    BRepLib.SameParameter_s(result, tol, True)
    ctx = fix.Context()
    return result, [TopoDS.Face(ctx.Apply(f)) for f in faces]
