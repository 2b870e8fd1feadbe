"""The fillet classification data model (the paper's section 3, steps 1 and 2).

Everything here is a frozen value. Faces, edges and vertices are named by stable 0-based
integer indices: index ``i`` is entry ``i + 1`` of the ``TopTools_IndexedMapOfShape`` (OCP 8:
``OCP.collections.IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher``) built
with ``TopExp.MapShapes_s`` on the classified solid (``Classification.face_map``,
``edge_map``, ``vertex_map`` of [Classification][medax.cad.model.Classification]), so
``classification.face(i)`` returns the ``TopoDS_Face`` of face ``i`` and the indices stay
valid as long as the solid (``Classification.shape``) is not modified.

Face classes (paper, step 1):

- ``fillet``: an edge blend, a 4-sided rolling-ball face between two supporting faces
  (constant or variable radius), see [FilletRecord][medax.cad.model.FilletRecord];
- ``corner_blend``: a blend where three or more fillets meet (the paper's point-transition
  fillet), see [CornerRecord][medax.cad.model.CornerRecord];
- ``supporting``: a non-blend face joined to a blend by a smooth (tangent) edge;
- ``protection``: every other face.

Edge classes (paper, step 2; meaningful on the edges of supporting faces, computed for all):

- ``smooth``: a tangent edge between a blend face and a supporting face (a fillet constraint);
- ``semi_smooth``: not smooth, but one of its vertices lies on a smooth edge;
- ``non_smooth``: the rest.

Lengths are in the file's length unit (``Classification.unit``), angles in radians.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any


class FaceClass(StrEnum):
    """Class of a face (the JSON report writes ``.value``)."""

    FILLET = "fillet"
    CORNER_BLEND = "corner_blend"
    SUPPORTING = "supporting"
    PROTECTION = "protection"


class EdgeClass(StrEnum):
    """Class of an edge (the JSON report writes ``.value``)."""

    SMOOTH = "smooth"
    SEMI_SMOOTH = "semi_smooth"
    NON_SMOOTH = "non_smooth"


BLEND_CLASSES = (FaceClass.FILLET, FaceClass.CORNER_BLEND)
"""The face classes that are blends."""


@dataclass(frozen=True)
class FaceInfo:
    """One face of the solid, with its class.

    Attributes
    ----------
    index : int
        The face's index (entry ``index + 1`` of the face map).
    cls : FaceClass
        Its class.
    surface : str
        The OCCT surface type in lower case (``plane``, ``cylinder``, ``cone``, ``sphere``,
        ``torus``, ``bspline``, ``bezier``, ``revolution``, ``extrusion``, ``offset``,
        ``other``).
    area : float
        Area, in the unit squared.
    centroid : tuple of float
        Centre of mass of the face ``(x, y, z)``.
    edges : tuple of int
        The face's edge indices (each once, seams included).
    neighbours : tuple of int
        The other faces sharing an edge with it (sorted).
    radius : float or None
        The blend radius where constant (fillets and corner blends only), else None.
    """

    index: int
    cls: FaceClass
    surface: str
    area: float
    centroid: tuple[float, float, float]
    edges: tuple[int, ...]
    neighbours: tuple[int, ...]
    radius: float | None = None


@dataclass(frozen=True)
class EdgeInfo:
    """One edge of the solid, with its class and tangency.

    Attributes
    ----------
    index : int
        The edge's index (entry ``index + 1`` of the edge map).
    cls : EdgeClass
        Its class.
    faces : tuple of int
        The faces containing it: two for a manifold edge; one for a seam, which bounds the
        same face twice, or for a free edge.
    vertices : tuple of int
        Its vertex indices (one for a closed edge).
    tangent : bool
        The numerical tangency test: ``max_angle`` is below the tangency tolerance (a seam
        is tangent; a free edge is not).
    max_angle : float
        The largest angle (radians) between the two faces' normals over samples along the
        edge.
    length : float
        Length, in the unit of the file.
    curve : str
        The OCCT curve type in lower case (``line``, ``circle``, ``ellipse``, ``hyperbola``,
        ``parabola``, ``bezier``, ``bspline``, ``offset``, ``other``; ``degenerate`` for a
        degenerate edge).
    is_free : bool
        The edge bounds only one face and is not a seam.
    """

    index: int
    cls: EdgeClass
    faces: tuple[int, ...]
    vertices: tuple[int, ...]
    tangent: bool
    max_angle: float
    length: float
    curve: str = "other"
    is_free: bool = False

    @property
    def is_seam(self) -> bool:
        """True when the edge bounds a single face twice (closed surfaces)."""
        return len(self.faces) == 1 and not self.is_free


@dataclass(frozen=True)
class FilletRecord:
    """An edge fillet: a 4-sided blend face between two supporting faces.

    Following the face's outer wire: smooth side 0, cross edge 0, smooth side 1, cross
    edge 1.

    Attributes
    ----------
    face : int
        The fillet's face index.
    smooth_edges : tuple of two tuples of int
        ``smooth_edges[k]`` is the chain of edges (usually one) of constraint side ``k`` in
        the face's wire order; these are tangent to ``supporting[k]``.
    cross_edges : tuple of int
        The start and end sides, one edge index each (for a fillet closed around an axis,
        e.g. a torus around a boss, both are the seam edge).
    supporting : tuple of int
        The supporting faces across the constraint sides; the two may be the same face (a
        fillet inside a slot), and one may itself be a blend when a fillet was rolled over
        an earlier fillet.
    radius : float or None
        The rolling-ball radius where constant, else None.
    closed : bool
        The fillet closes around an axis (both cross edges are its seam).
    """

    face: int
    smooth_edges: tuple[tuple[int, ...], tuple[int, ...]]
    cross_edges: tuple[int, int]
    supporting: tuple[int, int]
    radius: float | None
    closed: bool = False

    @property
    def constraint_edges(self) -> tuple[int, int]:
        """The two smooth edges, when each constraint side is one edge.

        Raises
        ------
        ValueError
            A constraint side has several edges.
        """
        a, b = self.smooth_edges
        if len(a) != 1 or len(b) != 1:
            raise ValueError(f"fillet face {self.face}: a constraint side has several edges")
        return a[0], b[0]


@dataclass(frozen=True)
class CornerRecord:
    """A corner blend (point-transition fillet) where three or more fillets meet.

    Attributes
    ----------
    face : int
        The corner blend's face index.
    fillets : tuple of int
        The blend faces (fillets or other corner blends) joined to it.
    supporting : tuple of int
        The non-blend faces it touches by a tangent edge.
    edges : tuple of int
        All its edges.
    radius : float or None
        The sphere's radius for a spherical corner, else None.
    """

    face: int
    fillets: tuple[int, ...]
    supporting: tuple[int, ...]
    edges: tuple[int, ...]
    radius: float | None


@dataclass(frozen=True)
class Doubt:
    """A face the classifier was not sure about.

    Attributes
    ----------
    face : int
        The face index.
    reason : str
        Why, in one line.
    """

    face: int
    reason: str


@dataclass(frozen=True)
class Classification:
    """Faces, edges and blend records of one solid.

    Attributes
    ----------
    faces : tuple of FaceInfo
        Every face, ``faces[i].index == i``.
    edges : tuple of EdgeInfo
        Every edge, ``edges[j].index == j``.
    fillets : tuple of FilletRecord
        The edge fillets.
    corners : tuple of CornerRecord
        The corner blends.
    shape : TopoDS_Solid
        The classified (healed) solid.
    face_map, edge_map, vertex_map : TopTools_IndexedMapOfShape
        The OCCT indexed maps the indices refer to (index ``i`` is map entry ``i + 1``).
    unit : str
        The length unit (e.g. ``"mm"``).
    source : str
        The file (or a label).
    solid : int
        Which solid of the file (0-based).
    tangent_angle : float
        The tolerance used by the tangency test (radians).
    doubts : tuple of Doubt
        The faces the classifier was not sure about.
    """

    faces: tuple[FaceInfo, ...]
    edges: tuple[EdgeInfo, ...]
    fillets: tuple[FilletRecord, ...]
    corners: tuple[CornerRecord, ...]
    shape: Any = field(repr=False, compare=False)
    face_map: Any = field(repr=False, compare=False)
    edge_map: Any = field(repr=False, compare=False)
    vertex_map: Any = field(repr=False, compare=False)
    unit: str = "mm"
    source: str = ""
    solid: int = 0
    tangent_angle: float = 1e-3
    doubts: tuple[Doubt, ...] = ()

    def __repr__(self) -> str:
        c = self.counts()
        classes = ", ".join(f"{c[k.value]} {k.value}" for k in FaceClass)
        return (
            f"Classification({self.source or 'shape'} solid {self.solid}: {c['faces']} faces: "
            f"{classes}; {len(self.doubts)} doubts)"
        )

    # ---- access to OCCT shapes ------------------------------------------------------------
    def face(self, i: int) -> Any:
        """Give the OCCT face of a face index.

        Parameters
        ----------
        i : int
            The face index (0-based).

        Returns
        -------
        TopoDS_Face
            The face, from the face map.
        """
        from OCP.TopoDS import TopoDS

        return TopoDS.Face(self.face_map.FindKey(i + 1))

    def edge(self, j: int) -> Any:
        """Give the OCCT edge of an edge index.

        Parameters
        ----------
        j : int
            The edge index (0-based).

        Returns
        -------
        TopoDS_Edge
            The edge, from the edge map.
        """
        from OCP.TopoDS import TopoDS

        return TopoDS.Edge(self.edge_map.FindKey(j + 1))

    def vertex(self, k: int) -> Any:
        """Give the OCCT vertex of a vertex index.

        Parameters
        ----------
        k : int
            The vertex index (0-based).

        Returns
        -------
        TopoDS_Vertex
            The vertex, from the vertex map.
        """
        from OCP.TopoDS import TopoDS

        return TopoDS.Vertex(self.vertex_map.FindKey(k + 1))

    # ---- queries --------------------------------------------------------------------------
    def indices(self, cls: FaceClass | str) -> tuple[int, ...]:
        """List the faces of one class.

        Parameters
        ----------
        cls : FaceClass or str
            A [FaceClass][medax.cad.model.FaceClass] or its value.

        Returns
        -------
        tuple of int
            The face indices, in order.
        """
        c = FaceClass(cls)
        return tuple(f.index for f in self.faces if f.cls is c)

    @property
    def blends(self) -> tuple[int, ...]:
        """Indices of all blend faces (fillets and corner blends)."""
        return tuple(f.index for f in self.faces if f.cls in BLEND_CLASSES)

    def fillet_of(self, face: int) -> FilletRecord | None:
        """Find the fillet record of a face.

        Parameters
        ----------
        face : int
            The face index.

        Returns
        -------
        FilletRecord or None
            Its [FilletRecord][medax.cad.model.FilletRecord], None when it is no fillet.
        """
        for rec in self.fillets:
            if rec.face == face:
                return rec
        return None

    def edge_classes(self, face: int) -> dict[int, EdgeClass]:
        """Give the class of each edge of a face (paper, step 2, for supporting faces).

        Parameters
        ----------
        face : int
            The face index.

        Returns
        -------
        dict of int to EdgeClass
            Edge index -> class.
        """
        return {j: self.edges[j].cls for j in self.faces[face].edges}

    def counts(self) -> dict[str, int]:
        """Number of faces per class value (all four present), and ``faces``, ``edges``."""
        c = Counter(f.cls.value for f in self.faces)
        out = {k.value: int(c.get(k.value, 0)) for k in FaceClass}
        out["faces"] = len(self.faces)
        out["edges"] = len(self.edges)
        return out
