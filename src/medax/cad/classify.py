"""Fillet recognition without the fillet builder's history (paper, section 3, steps 1-2).

Rules, applied to the healed solid:

1. Edge tangency is measured (:func:`medax.cad.topology.tangency`).
2. An **edge fillet** is a curved face whose outer wire, labelled edge by edge as *spring*
   (running along the least-curvature direction) or *cross* (along the most-curvature
   direction), reads spring-side, cross-side, spring-side, cross-side; every spring edge is
   tangent to a neighbour face; and its cross-section turns the normal by less than
   ``pi - SLOT_SWEEP_MARGIN``. The last rule is the slot trap: the half-cylinder end of a
   slot (or a rounded tab end) is tangent to two walls like a fillet, but its walls are
   parallel, its section sweeps 180 degrees and removing it would leave no edge: it is not
   a fillet, and is reported as a doubt.
3. A **corner blend** is a curved face, not an edge fillet, tangent to at least two blend
   faces across edges that are *cross* edges of those blends (fillets end on it; a support
   touches a fillet along a spring edge instead). Repeated until nothing changes, so corner
   blends next to corner blends are found.
4. **Supporting** faces: non-blend faces with a smooth edge; the rest are **protection**.
5. Edges: ``smooth`` (tangent, between a blend and a non-blend face), ``semi_smooth`` (a
   vertex on a smooth edge), ``non_smooth`` (the rest).
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from typing import Any

import numpy as np
from OCP.BRepGProp import BRepGProp
from OCP.GProp import GProp_GProps

from medax import tolerances
from medax._progress import log_progress
from medax.cad.face_geometry import (
    WireEdge,
    area_centroid,
    blend_radius,
    curve_type,
    normal_sweep,
    outer_wire_edges,
    surface_type,
)
from medax.cad.model import (
    BLEND_CLASSES,
    Classification,
    CornerRecord,
    Doubt,
    EdgeClass,
    EdgeInfo,
    FaceClass,
    FaceInfo,
    FilletRecord,
)
from medax.cad.topology import Topology, build_topology, tangency
from medax.errors import CadError

log = logging.getLogger(__name__)

#: a blend's cross-section must turn the normal by less than pi minus this (radians)
SLOT_SWEEP_MARGIN = 1e-3
#: ... and by more than this (radians): a nearly flat curved face is not a blend
MIN_SWEEP = 1e-3


def classify_solid(
    solid: Any,
    angle_tol: float = tolerances.TANGENT_ANGLE,
    source: str = "",
    unit: str = "mm",
    index: int = 0,
) -> Classification:
    """Classify the faces and edges of ``solid`` (a healed ``TopoDS_Solid``).

    ``angle_tol`` (radians) is the tangency tolerance. Raises :class:`CadError` if OCCT
    fails (the message names the file, and the face index where known).
    """
    try:
        return _classify(solid, angle_tol, source, unit, index)
    except CadError:
        raise
    except Exception as err:  # OCCT Standard_Failure and friends, translated here
        raise CadError(
            f"{source or 'shape'}: solid {index}: classification failed ({err})"
        ) from err


def _classify(solid: Any, angle_tol: float, source: str, unit: str, index: int) -> Classification:
    topo = build_topology(solid)
    if topo.n_faces == 0:
        raise CadError(f"{source or 'shape'}: solid {index} has no faces")
    tangent, angles = tangency(topo, angle_tol)
    doubts: list[Doubt] = []
    surfaces = [surface_type(topo.face(i)) for i in range(topo.n_faces)]

    wires: dict[int, list[WireEdge]] = {}
    fillets: dict[int, FilletRecord] = {}
    for i in range(topo.n_faces):
        log_progress(log, f"{source or 'shape'}: faces examined for fillets", i + 1, topo.n_faces)
        if surfaces[i] == "plane":
            continue
        try:
            wires[i] = outer_wire_edges(topo, i)
            rec = _edge_fillet(topo, i, wires[i], tangent, doubts)
        except CadError:
            raise
        except Exception as err:
            raise CadError(f"{source or 'shape'}: face {i}: OCCT failed ({err})") from err
        if rec is not None:
            fillets[i] = rec

    corners = _corner_blends(topo, surfaces, wires, fillets, tangent)
    blend = set(fillets) | set(corners)
    _near_misses(topo, surfaces, wires, blend, tangent, doubts)
    edge_cls = _edge_classes(topo, tangent, blend)
    faces = _faces(topo, surfaces, blend, fillets, corners, edge_cls)
    edges = tuple(
        EdgeInfo(
            index=j,
            cls=edge_cls[j],
            faces=topo.edge_faces[j],
            vertices=topo.edge_vertices[j],
            tangent=bool(tangent[j]),
            max_angle=float(angles[j]),
            length=_edge_length(topo.edge(j)),
            curve=curve_type(topo.edge(j)) if not topo.degenerate[j] else "degenerate",
            is_free=len(topo.edge_faces[j]) == 1 and angles[j] >= math.pi,
        )
        for j in range(topo.n_edges)
    )
    return Classification(
        faces=faces,
        edges=edges,
        fillets=tuple(fillets[i] for i in sorted(fillets)),
        corners=tuple(corners[i] for i in sorted(corners)),
        shape=solid,
        face_map=topo.face_map,
        edge_map=topo.edge_map,
        vertex_map=topo.vertex_map,
        unit=unit,
        source=source,
        solid=index,
        tangent_angle=angle_tol,
        doubts=tuple(doubts),
    )


# ---- edge fillets -------------------------------------------------------------------------
def _runs(wire: list[WireEdge]) -> list[list[WireEdge]]:
    """Cyclic runs of consecutive wire edges of the same kind."""
    if not wire:
        return []
    # rotate so the wire starts at a kind change
    n = len(wire)
    start = next((k for k in range(n) if wire[k].kind != wire[k - 1].kind), 0)
    rot = wire[start:] + wire[:start]
    runs: list[list[WireEdge]] = [[rot[0]]]
    for w in rot[1:]:
        if w.kind == runs[-1][-1].kind:
            runs[-1].append(w)
        else:
            runs.append([w])
    return runs


def _edge_fillet(
    topo: Topology,
    i: int,
    wire: list[WireEdge],
    tangent: np.ndarray,
    doubts: list[Doubt],
) -> FilletRecord | None:
    runs = _runs(wire)
    kinds = [r[0].kind for r in runs]
    if len(runs) != 4 or kinds.count("spring") != 2 or kinds.count("cross") != 2:
        return None
    k0 = kinds.index("spring")
    springs = (runs[k0], runs[(k0 + 2) % 4])
    crosses = (runs[(k0 + 1) % 4], runs[(k0 + 3) % 4])
    supports: list[int] = []
    for side in springs:
        nbrs: Counter[int] = Counter()
        for w in side:
            if not tangent[w.edge]:
                return None
            others = [f for f in topo.edge_faces[w.edge] if f != i]
            if not others:
                return None  # a seam as a spring side: a closed surface, not a blend
            nbrs.update(others)
        supports.append(nbrs.most_common(1)[0][0])
    if any(len(c) != 1 for c in crosses):
        return None  # a cross side of several edges: not the 4-sided blend the paper uses
    mid0 = np.array(springs[0][len(springs[0]) // 2].mid_uv)
    mid1 = np.array(springs[1][len(springs[1]) // 2].mid_uv)
    sweep = normal_sweep(topo.face(i), mid0, mid1)
    if not np.isfinite(sweep) or sweep < MIN_SWEEP:
        return None
    if sweep > math.pi - SLOT_SWEEP_MARGIN:
        doubts.append(
            Doubt(
                i,
                f"tangent to faces {supports[0]} and {supports[1]} like a fillet, but its "
                f"section sweeps {math.degrees(sweep):.1f} deg (slot or tab end): not a blend",
            )
        )
        return None
    c0, c1 = crosses[0][0].edge, crosses[1][0].edge
    return FilletRecord(
        face=i,
        smooth_edges=(tuple(w.edge for w in springs[0]), tuple(w.edge for w in springs[1])),
        cross_edges=(c0, c1),
        supporting=(supports[0], supports[1]),
        radius=blend_radius(topo.face(i)),
        closed=c0 == c1,
    )


# ---- corner blends ------------------------------------------------------------------------
def _corner_blends(
    topo: Topology,
    surfaces: list[str],
    wires: dict[int, list[WireEdge]],
    fillets: dict[int, FilletRecord],
    tangent: np.ndarray,
) -> dict[int, CornerRecord]:
    cross_of: dict[int, set[int]] = {i: set(r.cross_edges) for i, r in fillets.items()}
    corners: dict[int, CornerRecord] = {}
    changed = True
    while changed:
        changed = False
        for i in wires:
            if i in fillets or i in corners or surfaces[i] == "plane":
                continue
            blends, supports = set(), set()
            for j in topo.face_edges[i]:
                if not tangent[j]:
                    continue
                for f in topo.edge_faces[j]:
                    if f == i:
                        continue
                    if j in cross_of.get(f, ()) or f in corners:
                        blends.add(f)
                    elif f not in fillets:
                        supports.add(f)
            if len(blends) >= 2:
                corners[i] = CornerRecord(
                    face=i,
                    fillets=tuple(sorted(blends)),
                    supporting=tuple(sorted(supports)),
                    edges=topo.face_edges[i],
                    radius=blend_radius(topo.face(i)),
                )
                cross_of[i] = set(topo.face_edges[i])
                changed = True
    return corners


def _near_misses(
    topo: Topology,
    surfaces: list[str],
    wires: dict[int, list[WireEdge]],
    blend: set[int],
    tangent: np.ndarray,
    doubts: list[Doubt],
) -> None:
    """Doubt: curved non-blend faces tangent to non-blend neighbours (one-sided tangency,
    more than four sides): looked like blends, were not taken as such."""
    seen = {d.face for d in doubts}
    for i in range(topo.n_faces):
        if surfaces[i] == "plane" or i in blend or i in seen:
            continue
        nbrs = sorted(
            {
                f
                for j in topo.face_edges[i]
                if tangent[j]
                for f in topo.edge_faces[j]
                if f != i and f not in blend
            }
        )
        if nbrs:
            n_edges = len(wires.get(i, ())) or len(topo.face_edges[i])
            radius = blend_radius(topo.face(i))
            r = "" if radius is None else f" r={radius:.6g}"
            doubts.append(
                Doubt(
                    i,
                    f"{surfaces[i]}{r} face ({n_edges} wire edges) tangent to faces {nbrs}, but "
                    f"not 4-sided with both spring sides tangent (notched or one-sided "
                    f"blend?): not taken as a blend",
                )
            )


# ---- edges and faces ----------------------------------------------------------------------
def _edge_classes(topo: Topology, tangent: np.ndarray, blend: set[int]) -> list[EdgeClass]:
    smooth = [
        bool(tangent[j])
        and len(topo.edge_faces[j]) == 2
        and len(blend.intersection(topo.edge_faces[j])) == 1
        for j in range(topo.n_edges)
    ]
    smooth_vertices = {v for j in range(topo.n_edges) if smooth[j] for v in topo.edge_vertices[j]}
    out = []
    for j in range(topo.n_edges):
        if smooth[j]:
            out.append(EdgeClass.SMOOTH)
        elif smooth_vertices.intersection(topo.edge_vertices[j]):
            out.append(EdgeClass.SEMI_SMOOTH)
        else:
            out.append(EdgeClass.NON_SMOOTH)
    return out


def _faces(
    topo: Topology,
    surfaces: list[str],
    blend: set[int],
    fillets: dict[int, FilletRecord],
    corners: dict[int, CornerRecord],
    edge_cls: list[EdgeClass],
) -> tuple[FaceInfo, ...]:
    out = []
    for i in range(topo.n_faces):
        if i in fillets:
            cls, radius = FaceClass.FILLET, fillets[i].radius
        elif i in corners:
            cls, radius = FaceClass.CORNER_BLEND, corners[i].radius
        elif any(edge_cls[j] is EdgeClass.SMOOTH for j in topo.face_edges[i]):
            cls, radius = FaceClass.SUPPORTING, None
        else:
            cls, radius = FaceClass.PROTECTION, None
        area, centroid = area_centroid(topo.face(i))
        nbrs = sorted({f for j in topo.face_edges[i] for f in topo.edge_faces[j] if f != i})
        out.append(
            FaceInfo(
                index=i,
                cls=cls,
                surface=surfaces[i],
                area=area,
                centroid=centroid,
                edges=topo.face_edges[i],
                neighbours=tuple(nbrs),
                radius=radius,
            )
        )
    assert all(f.cls in BLEND_CLASSES for f in out if f.index in blend)
    return tuple(out)


def _edge_length(edge: Any) -> float:
    props = GProp_GProps()
    BRepGProp.LinearProperties_s(edge, props)
    return float(props.Mass())


def classify_file(path: str, angle_tol: float = tolerances.TANGENT_ANGLE) -> list[Classification]:
    """Read ``path`` (STEP/IGES/BRep) and classify each of its solids."""
    from medax.cad.reader import read_part

    part = read_part(path)
    return [
        classify_solid(s, angle_tol, source=part.source, unit=part.unit, index=k)
        for k, s in enumerate(part.solids)
    ]
