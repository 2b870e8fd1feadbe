"""The 4-sided region: four side curves in counter-clockwise order and an embedding."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from medax import tolerances
from medax.errors import RegionError
from medax.geometry import kernels
from medax.geometry._rows import points2d
from medax.geometry._types import FloatArray
from medax.geometry.crossing_kernel import polylines_cross, self_crossing
from medax.geometry.curve import Curve
from medax.geometry.embedded_curve import EmbeddedCurve
from medax.geometry.embedding import Embedding, PlaneEmbedding
from medax.geometry.simple_boundary import check_simple

PAIRS: tuple[tuple[int, int], ...] = ((0, 2), (1, 3))
"""The two pairs of opposite sides."""
_SAMPLES = 200  # samples per side for orientation and crossing checks


@dataclass(frozen=True)
class PairRoles:
    """Which sides play which role for one choice of constraint pair.

    Attributes
    ----------
    a1, a2 : int
        The constraints ``S_k`` and ``S_{k+2}``.
    b1 : int
        The start side ``S_{k-1}`` (where ``a1`` starts).
    b2 : int
        The end side ``S_{k+1}``.
    """

    a1: int
    a2: int
    b1: int
    b2: int


def pair_roles(pair: tuple[int, int]) -> PairRoles:
    """Give the roles of the sides for one pair of constraint sides.

    Parameters
    ----------
    pair : tuple of int
        The constraints, ``(0, 2)`` or ``(1, 3)``.

    Returns
    -------
    PairRoles
        Constraints ``a1 = pair[0]``, ``a2 = pair[1]``, start and end sides
        ([PairRoles][medax.geometry.region.PairRoles]).

    Raises
    ------
    RegionError
        ``pair`` is neither ``(0, 2)`` nor ``(1, 3)``.
    """
    if tuple(pair) not in PAIRS:
        raise RegionError(f"pair must be (0, 2) or (1, 3), got {tuple(pair)}")
    k = pair[0]
    return PairRoles(a1=k, a2=(k + 2) % 4, b1=(k + 3) % 4, b2=(k + 1) % 4)


@dataclass(frozen=True)
class Region:
    """A 4-sided region: four side curves in the parameter plane and an embedding.

    The sides ``S0..S3`` run counter-clockwise, side k from corner k to k+1. Build with
    [Region.build][medax.geometry.region.Region.build], which checks and orients. Lengths
    are in the region's unit; distances are measured in space.

    Attributes
    ----------
    sides : tuple of 4 Curve
        The side curves in the parameter plane.
    embedding : Embedding
        Maps the parameter plane to space (identity for a planar region).
    name : str
        Names the region in messages.
    reoriented : bool
        The input was clockwise and was reversed (sides 1 and 3 swapped).
    space_sides : tuple of 4 Curve or None
        The sides in space exactly, if given (else ``E(S_k)``).
    """

    sides: tuple[Curve, Curve, Curve, Curve]
    embedding: Embedding = field(default_factory=PlaneEmbedding)
    name: str = "region"
    reoriented: bool = False
    space_sides: tuple[Curve, Curve, Curve, Curve] | None = None

    @classmethod
    def build(
        cls,
        sides: Sequence[Curve],
        name: str = "region",
        embedding: Embedding | None = None,
        space_sides: Sequence[Curve] | None = None,
        check: bool = True,
    ) -> Region:
        """Build a region from four sides, checked and oriented counter-clockwise.

        Clockwise input is reversed: sides 0 and 2 keep their numbers, sides 1 and 3 swap,
        so pairs (0, 2) and (1, 3) still mean the same two sides; ``reoriented`` says so
        (``medax.axis.export`` reports sides in the input's numbering).

        Parameters
        ----------
        sides : sequence of 4 Curve
            The side curves in the parameter plane, side k from corner k to k+1.
        name : str
            Names the region in messages.
        embedding : Embedding, optional
            Maps the parameter plane to space (default: the plane itself).
        space_sides : sequence of 4 Curve, optional
            The sides in space exactly.
        check : bool
            Check closed corners, no zero-length side and no crossings
            ([check][medax.geometry.region.Region.check]).

        Returns
        -------
        Region
            The region, counter-clockwise in the parameter plane.

        Raises
        ------
        RegionError
            Not 4 sides, or a check fails (the message names the side or corner).
        """
        if len(sides) != 4:
            raise RegionError(f"region '{name}' needs 4 sides, got {len(sides)}")
        emb = embedding if embedding is not None else PlaneEmbedding()
        s4 = (sides[0], sides[1], sides[2], sides[3])
        sp4 = None if space_sides is None else tuple(space_sides)
        region = cls(s4, emb, name, False, sp4)  # type: ignore[arg-type]
        if check:
            region.check()
        if region.signed_area() < 0.0:
            flip = (s4[0].reversed(), s4[3].reversed(), s4[2].reversed(), s4[1].reversed())
            sflip = None
            if sp4 is not None:
                sflip = (sp4[0].reversed(), sp4[3].reversed(), sp4[2].reversed(), sp4[1].reversed())
            region = cls(flip, emb, name, True, sflip)
        return region

    # ---- geometry -------------------------------------------------------------------------
    @property
    def corners(self) -> FloatArray:
        """Corner k = start of side k, shape ``(4, 2)``."""
        return np.array([s.start for s in self.sides])

    def space_curve(self, k: int) -> Curve:
        """Give a side as a curve in space, where distances are measured.

        Parameters
        ----------
        k : int
            The side, 0..3.

        Returns
        -------
        Curve
            The exact space side if given, else the side mapped by the embedding.
        """
        if self.space_sides is not None:
            return self.space_sides[k]
        if self.embedding.is_identity:
            return self.sides[k]
        return self._embedded[k]

    @cached_property
    def _embedded(self) -> tuple[Curve, ...]:
        return tuple(EmbeddedCurve(s, self.embedding) for s in self.sides)

    @cached_property
    def _side_samples(self) -> tuple[FloatArray, ...]:
        """``_SAMPLES`` points of each side at equal parameter steps (each (n, 2)), shared
        by the checks and the boundary."""
        return tuple(s.sample(_SAMPLES) for s in self.sides)

    @cached_property
    def boundary(self) -> FloatArray:
        """Closed sampled boundary in the parameter plane, shape ``(4 * n, 2)``."""
        return np.concatenate([p[:-1] for p in self._side_samples])

    @cached_property
    def diagonal(self) -> float:
        """Diagonal of the bounding box of the region in space: the length scale."""
        if self.embedding.is_identity and self.space_sides is None:
            # the sides' samples are the boundary's (each side's last is the next's first)
            pts = self.boundary
        else:
            pts = np.concatenate([self.space_curve(k).sample(_SAMPLES) for k in range(4)])
        return float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0)))

    def signed_area(self) -> float:
        """Signed area in the parameter plane (> 0 for counter-clockwise).

        Summed relative to the first corner so that it does not cancel far from the origin.
        """
        b = self.boundary - self.boundary[0]
        x, y = b[:, 0], b[:, 1]
        return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))

    def side_lengths(self) -> FloatArray:
        """Lengths of the four sides in space, shape ``(4,)``."""
        return np.array([self.space_curve(k).length() for k in range(4)])

    def contains(self, p: FloatArray) -> np.ndarray:
        """Test whether parameter points are inside the region.

        Even-odd crossing count against the sampled boundary, all points and edges at once.

        Parameters
        ----------
        p : ndarray
            Points (n, 2) or (2,) in the parameter plane.

        Returns
        -------
        ndarray
            Booleans (n,).
        """
        q = points2d(p)
        ay, by, ax, dx, dy = self._edges
        px, py = q[:, 0:1], q[:, 1:2]
        # the edges each point's horizontal ray may cross (few of the n x m pairs), then
        # where they cross it
        i, j = ((ay > py) != (by > py)).nonzero()
        x_cross = ax[j] + (py[i, 0] - ay[0, j]) * dx[j] / dy[j]
        hits = np.bincount(i[px[i, 0] < x_cross], minlength=len(q))
        return np.asarray(hits % 2 == 1)

    @cached_property
    def _edges(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """The closed boundary's edges for :meth:`contains`: start and end ``y`` (1, m)
        each, start ``x``, ``dx`` and ``dy`` (m,) each."""
        a = self.boundary
        b = np.roll(a, -1, axis=0)
        return (
            a[None, :, 1].copy(),
            b[None, :, 1].copy(),
            a[:, 0].copy(),
            b[:, 0] - a[:, 0],
            b[:, 1] - a[:, 1],
        )

    # ---- checks ---------------------------------------------------------------------------
    def check(self) -> None:
        """Check the sides: closed corners, no zero-length side, no crossings.

        Corners must meet within ``CORNER_TOL`` x diagonal and sides be longer than
        ``MIN_SIDE`` x diagonal ([medax.tolerances][medax.tolerances]).

        Raises
        ------
        RegionError
            Naming the side or corner that is wrong.
        """
        pts = np.concatenate(self._side_samples)
        with np.errstate(over="ignore", invalid="ignore"):
            diag = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0)))
        if not np.isfinite(diag):
            raise RegionError(f"region '{self.name}': coordinates too large (sizes overflow)")
        if diag == 0.0:
            raise RegionError(f"region '{self.name}' is degenerate (all points coincide)")
        for k, s in enumerate(self.sides):
            if s.dim != 2:
                raise RegionError(f"region '{self.name}': side {k} is not a 2-D curve")
            if s.length() <= tolerances.MIN_SIDE * diag:
                raise RegionError(f"region '{self.name}': side {k} has zero length")
        # corners meet to the tolerance, or to what doubles resolve far from the origin
        corner_tol = max(tolerances.CORNER_TOL * diag, 16.0 * float(np.spacing(np.abs(pts).max())))
        for k in range(4):
            gap = float(np.linalg.norm(self.sides[k].end - self.sides[(k + 1) % 4].start))
            if gap > corner_tol:
                raise RegionError(
                    f"region '{self.name}': side {k} ends {self.sides[k].end.tolist()} but side "
                    f"{(k + 1) % 4} starts {self.sides[(k + 1) % 4].start.tolist()} "
                    f"(corner {(k + 1) % 4} open by {gap:.3g})"
                )
        self._check_crossings(diag)
        if self.embedding.is_identity:
            check_simple(self.sides, diag, self.name)

    def _check_crossings(self, diag: float) -> None:
        """Sides crossing each other or themselves (compiled chunked tests,
        :mod:`medax.geometry.crossing_kernel`)."""
        kernels.announce_compile()
        polys = [np.ascontiguousarray(p) for p in self._side_samples]
        for i in range(4):
            for j in range(i + 1, 4):
                a, b = polys[i], polys[j]
                # adjacent sides share a corner: drop the segments touching it
                if j == i + 1:
                    a, b = a[:-2], b[2:]
                elif i == 0 and j == 3:
                    a, b = a[2:], b[:-2]
                if polylines_cross(a, b, 1e-12 * diag):
                    raise RegionError(f"region '{self.name}': side {i} crosses side {j}")
        for i, p in enumerate(polys):
            if self_crossing(p, 1e-12 * diag):
                raise RegionError(f"region '{self.name}': side {i} crosses itself")


def normalised_region(region: Region) -> tuple[Region, FloatArray, float]:
    """Move a planar region to the origin and scale it to unit diagonal.

    Work done there keeps its relative accuracy far from the origin and in any unit. Regions
    on surfaces are returned unchanged (offset 0, scale 1).

    Parameters
    ----------
    region : Region
        The region (not modified).

    Returns
    -------
    work : Region
        The normalised region.
    offset : ndarray
        Shape (2,); with ``scale`` maps it back: ``x = x' * scale + offset``.
    scale : float
        The region's diagonal.
    """
    if not region.embedding.is_identity:
        return region, np.zeros(2), 1.0
    pts = region.boundary
    offset = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
    scale = region.diagonal
    sides = tuple(s.transformed(offset, scale) for s in region.sides)
    work = Region(sides, region.embedding, region.name, region.reoriented)  # type: ignore[arg-type]
    # the image's samples are the samples' images: its boundary and diagonal in closed form
    work.__dict__["boundary"] = (pts - offset) / scale
    work.__dict__["diagonal"] = 1.0
    return work, offset, scale
