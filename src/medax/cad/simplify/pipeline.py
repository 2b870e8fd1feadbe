"""Fillet simplification of a solid (the paper's section 3, steps 3 to 5).

[simplify][medax.cad.simplify.pipeline.simplify] splits every fillet it can handle along
its medial curve, merges each half into its supporting face on one surface (exact where
the geometry allows, fitted otherwise), rebuilds the solid on shared edges and validates it
against the original. Fillets it cannot handle are kept, each with its reason; when the
rebuilt solid fails validation the failing fillets themselves are found (the failure
blamed on their faces, else by bisection) and kept, their neighbours still simplified. The
input solid is never modified and an invalid solid is never returned: at worst the result
is the input itself with every fillet kept.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.GeomAbs import GeomAbs_Cylinder, GeomAbs_Plane
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_SHELL
from OCP.TopoDS import TopoDS

from medax import tolerances
from medax._progress import log_progress
from medax.cad.simplify.bridge import bridge_edge
from medax.cad.simplify.chains import Chain, chain_arcs, chain_specs, find_chains
from medax.cad.simplify.corner import corner_arcs, plane_normal
from medax.cad.simplify.cylinder_field import cylinder_surface
from medax.cad.simplify.fitted import (
    FittedSurface,
    GraphSetup,
    Refusal,
    graph_setup,
    graph_surface,
)
from medax.cad.simplify.groups import Group, GroupError, build_groups
from medax.cad.simplify.local_measure import (
    contributions,
    local_area_change,
    local_volume_change,
)
from medax.cad.simplify.medial import TRACED, Medial, medial_curve
from medax.cad.simplify.mitre import mitre_keeps, mitre_pairs
from medax.cad.simplify.occ import count, diagonal, shape_map
from medax.cad.simplify.rebuild import build_solid
from medax.cad.simplify.result import DEVIATION_SAMPLES, FaceGroup, SimplifyResult
from medax.cad.simplify.ring import NOT_A_RING, ring_surface
from medax.cad.simplify.search import Failure, halves_of, isolate, riders, volume_blame
from medax.cad.simplify.specs import BlendInput, CornerSpec, FilletSpec
from medax.cad.simplify.split import split_along
from medax.cad.simplify.surfaces import Half, MergedSurface, merged_surface
from medax.cad.simplify.validate import (
    area,
    area_change,
    check,
    default_volume,
    deviation,
    free_edge_faces,
    volume,
    volume_change,
)
from medax.errors import CadError

log = logging.getLogger(__name__)

#: Default deviation tolerance, relative to the part's diagonal (the issue's ``1e-5 x``).
DEVIATION_TOL = 1e-5
#: Largest accepted relative volume change.
VOLUME_TOL = 1e-6
#: Largest accepted relative change of the boundary's area: 25x the integrator's noise on
#: exact faces (up to 2.0e-7 on every part simplified, from NURBS copies of revolutions),
#: and below the 1.8e-5 more area of a merged face with a 0.35 mm bump in one pcurve, which
#: the analyzer and the sampled deviations passed.
AREA_TOL = 5e-6
#: Geometric tolerance of the construction, relative to the diagonal.
BUILD_TOL = tolerances.BUILD_TOL
#: A fitted surface is fitted to this share of the deviation tolerance (measured), and
#: taken up to ACCEPT_SHARE when no fit reaches it within its levels: the faces that reach
#: it keep their tangency across the medial curves (2e-3 rad on the 12-edge box; 9e-3 rad
#: when fitted to 0.4), and those whose fit stalls on a curvature jump off its knot lines
#: are merged (most of them stalled within 4x), still checked against the full tolerance.
FIT_SHARE, ACCEPT_SHARE = 0.1, 0.8
#: Deviation samples per face (n x n) for groups on a fitted surface.
FITTED_DEVIATION_SAMPLES = 12
#: Seconds the search for failing fillets may take after the first rebuild failed.
ISOLATION_BUDGET = 300.0
#: Riders tried one at a time as plain fillets on their kept base, at most (each try is a
#: pass over the fitted faces).
MAX_RIDER_TRIES = 8
#: Marker in the surface table: this supporting plane gets a fitted surface per attempt.
FITTED = "fitted"


@dataclass
class _Attempt:
    shape: Any
    groups: list[Group]
    faces: list[Any]
    deviation: float
    volume: float
    origin: tuple[int, ...]
    halves_origin: dict[int, list[int]]
    kinds: dict[int, str]
    fit_error: float = 0.0
    fit_dv: float = 0.0
    area_change: float = 0.0
    volume_before: float = 0.0  # the input's volume that ``volume`` is measured against


@dataclass
class _Job:
    """State shared by the steps of one :func:`simplify` run: the working copy and its
    maps, the medial curves, corner arcs, bridges ((rider, base) -> edge), merged surfaces,
    fitted-surface cache, the fillets
    still tried (``specs``), the blends kept with their reasons, and tolerances."""

    work: Any
    fmap: Any
    emap: Any
    diag: float
    tol: float
    say: Callable[[str], None]
    kept: dict[int, str]
    medials: dict[int, Medial] = field(default_factory=dict)
    specs: dict[int, FilletSpec] = field(default_factory=dict)
    corners: dict[int, CornerSpec] = field(default_factory=dict)
    arcs: dict[int, list[Any]] = field(default_factory=dict)
    bridges: dict[tuple[int, int], Any] = field(default_factory=dict)
    surfaces: dict[int, MergedSurface | str] = field(default_factory=dict)
    cache: dict[tuple[int, ...], FittedSurface | str] = field(default_factory=dict)
    # (support, member origins) -> the height-field fit's setup, shared by probe and full fit
    setups: dict[tuple[int, ...], GraphSetup | str] = field(default_factory=dict)
    # the last split kept by a fit round and the tool edges it was made with (:func:`_split`)
    last_split: tuple[list[Any], Any] | None = None
    exact: dict[tuple[Any, ...], MergedSurface | str] = field(default_factory=dict)
    area0: float | None = None  # the input's boundary area (measured at the first attempt)
    volume0: float | None = None  # the input's volume (measured at the first attempt)
    volume_ref: float | None = None  # its volume by the default integrator (a denominator)
    whole: dict[int, int] = field(default_factory=dict)  # fillet -> face it merges into whole
    # fillet -> its supporting face that has no surface for its half (why it was kept)
    no_surface: dict[int, int] = field(default_factory=dict)
    # fillets whose own piece held the misfit of that face (the face is fitted without them)
    own_misfit: set[int] = field(default_factory=set)
    # chains of tangent fillets (:mod:`.chains`): each goes whole or not at all
    chains: list[Chain] = field(default_factory=list)
    chain_links: set[tuple[int, int]] = field(default_factory=set)
    # rider -> (the fillet it rides on with no bridge, its medial curve, why it was kept)
    unbridged: dict[int, tuple[int, Medial, str]] = field(default_factory=dict)
    # whether cylinders the ring route refuses take the cylinder field (the second pass:
    # :func:`_cylinder_pass`), and the fillets a failing face drops first then
    cylinder_field: bool = False
    prefer: set[int] = field(default_factory=set)

    @property
    def vol0(self) -> float:
        """The input's volume (:func:`.validate.volume`), measured when first needed: a
        run in which no rebuild gets that far does without it (Gauss-Kronrod took 197 s on
        a 68-face part whose every fit failed)."""
        if self.volume0 is None:
            self.volume0 = volume(self.work)
        return self.volume0

    @property
    def vol_ref(self) -> float:
        """The input's volume by OCCT's default integrator: the denominator of the relative
        volume changes measured on the changed faces (1e-3 off changes a 1e-6 change by
        1e-9; Gauss-Kronrod on a 94-face input took 188 s where the denominator needs no
        digits from it). The whole-solid check compares with :attr:`vol0`."""
        if self.volume_ref is None:
            self.volume_ref = default_volume(self.work)
        return self.volume_ref

    @property
    def btol(self) -> float:
        """Length tolerance of the construction."""
        return BUILD_TOL * self.diag

    def face(self, i: int) -> Any:
        """Face ``i`` (0-based) of the working solid."""
        return TopoDS.Face(self.fmap.FindKey(i + 1))


def simplify(
    shape: Any,
    blends: BlendInput,
    tol: float = DEVIATION_TOL,
    progress: Callable[[str], None] | None = None,
    time_budget: float = ISOLATION_BUDGET,
) -> SimplifyResult:
    """Simplify the fillets of ``shape`` described by ``blends``.

    Parameters
    ----------
    shape : TopoDS_Shape
        One solid; it is not modified.
    blends : BlendInput
        The fillets and corner blends to remove, with their supporting faces (from a
        classification: ``specs_from_classification``).
    tol : float
        Deviation tolerance relative to the part's diagonal.
    progress : callable, optional
        Receives one-line messages (the CLI prints them on stderr); default: logging.
    time_budget : float
        Seconds the search for the failing fillets may take when the rebuild with all of
        them fails; fillets not tried by then are kept, with that reason.

    Returns
    -------
    SimplifyResult
        The validated solid and what was removed and kept.
    """
    t0 = time.perf_counter()
    say = progress or (lambda msg: log.info(msg))
    work = BRepBuilderAPI_Copy(shape, True, False).Shape()
    fmap = shape_map(work, TopAbs_FACE)
    job = _Job(
        work,
        fmap,
        shape_map(work, TopAbs_EDGE),
        diagonal(work),
        tol,
        say,
        dict(blends.refused),
    )
    nfaces, kept, diag = fmap.Size(), job.kept, job.diag
    for i, spec in enumerate(blends.fillets):
        log_progress(log, "medial curves of the fillets:", i + 1, len(blends.fillets))
        side0, side1 = (
            [TopoDS.Edge(job.emap.FindKey(i + 1)) for i in spec.side_edges(k)] for k in (0, 1)
        )
        m = medial_curve(job.face(spec.face), side0, side1, tol=job.btol)
        if isinstance(m, str):
            kept[spec.face] = m
        else:
            job.medials[spec.face] = m
    _chains(job, blends)
    _corners(job, blends)
    _bridges(job, blends)
    say(f"{len(job.medials)} fillets with a medial curve, {len(job.corners)} corner blends split")
    job.specs = {s.face: s for s in blends.fillets if s.face in job.medials}
    for ch in job.chains:
        if all(f in job.specs for f in ch.members):
            job.specs.update(chain_specs(ch))
    for f, why in mitre_keeps(mitre_pairs(work, fmap, job.specs), job.corners).items():
        job.specs.pop(f)
        kept[f] = why
    _cascade(job.specs, job.corners, kept, job.chains)
    _refresh_surfaces(job)
    n_fit = sum(1 for v in job.surfaces.values() if v == FITTED)
    say(f"{len(job.specs)} fillets on {len(job.surfaces)} merged faces ({n_fit} fitted)")

    def attempt(sel: dict[int, FilletSpec]) -> _Attempt | str:
        return _attempt(job, sel)

    before_fit, corners_before = dict(job.specs), dict(job.corners)
    if n_fit:
        _fit_pass(job)
    _one_sided(job, blends)
    # (after the fillets merged whole: a cylinder's newcomer must not take their place)
    if n_fit and _cylinder_pass(job, before_fit, corners_before):
        _one_sided(job, blends)
    job.cylinder_field = True
    _readmit_riders(job, blends)
    specs, corners = job.specs, job.corners
    first = attempt(specs) if specs else None
    result: _Attempt | None
    if isinstance(first, str):
        say(f"rebuild with all fillets failed ({first}); isolating the failing fillets")
        deadline = time.perf_counter() + time_budget
        together = [set(ch.members) for ch in job.chains]
        result, specs = isolate(specs, attempt, kept, say, deadline, first, together)
    else:
        result = first
    used_corners = (
        sorted(c for c, cs in corners.items() if set(cs.fillets) <= set(specs))
        if result is not None
        else []
    )
    for c in corners:
        if c not in used_corners:
            kept.setdefault(c, "a fillet meeting this corner blend was kept")
    removed = sorted(list(specs) + used_corners) if result is not None else []
    for f in specs:
        if result is None and f not in kept:
            kept[f] = "rebuild failed"
    if result is None:
        final, groups_out, dev = work, _identity_groups(nfaces), 0.0
        vol0 = vol1 = job.volume0 if job.volume0 is not None else job.vol_ref
        valid = check(work, with_volume=False).valid
    else:
        final, dev, vol1, valid = result.shape, result.deviation, result.volume, True
        vol0 = result.volume_before
        groups_out = _face_groups(result)
    notes = [] if removed else ["no fillet simplified: output equals input"]
    notes += [
        f"fillet {f} merged whole into face {s}: its other face has no surface for a half"
        for f, s in sorted(job.whole.items())
        if f in removed
    ]
    if not blends.fillets and not blends.refused:
        notes = ["no fillets found: output equals input"]
    return SimplifyResult(
        shape=final,
        faces_before=nfaces,
        faces_after=count(final, TopAbs_FACE),
        blends_removed=removed,
        blends_kept=sorted(kept.items()),
        valid=valid,
        volume_before=vol0,
        volume_after=vol1,
        max_deviation=dev,
        diagonal=diag,
        face_groups=groups_out,
        time_s=time.perf_counter() - t0,
        medial_error=max((job.medials[f].error for f in removed if f in job.medials), default=0.0),
        fit_error=result.fit_error if result is not None else 0.0,
        fit_volume_rel_change=result.fit_dv if result is not None else 0.0,
        area_rel_change=result.area_change if result is not None else 0.0,
        default_volume_rel_change=default_volume(final) / default_volume(shape) - 1.0,
        notes=notes,
        radii={spec.face: spec.radius for spec in blends.fillets},
    )


def _corners(job: _Job, blends: BlendInput) -> None:
    """Corner blends that can be split (a sphere between planes, every fillet meeting it
    with a medial curve) and their split arcs into ``job``; the others go to ``job.kept``."""
    by_face = {s.face: s for s in blends.fillets}
    for cs in blends.corners:
        missing = [f for f in cs.fillets if f not in job.medials]
        if missing:
            job.kept[cs.face] = f"corner blend: fillets {missing} meeting it are kept"
            continue
        normals = {}
        for sup in cs.supporting:
            n = plane_normal(job.face(sup))
            if n is None:
                break
            normals[sup] = n
        if len(normals) != len(cs.supporting):
            job.kept[cs.face] = "corner blend between faces that are not planes (not supported)"
            continue
        pairs = [(by_face[f].supporting[0], by_face[f].supporting[1]) for f in cs.fillets]
        r = corner_arcs(job.face(cs.face), pairs, normals)
        if isinstance(r, str):
            job.kept[cs.face] = r
            continue
        job.corners[cs.face], job.arcs[cs.face] = cs, r[0]


def _chains(job: _Job, blends: BlendInput) -> None:
    """Chains of tangent fillets (see :mod:`.chains`) into ``job.chains``. A chain
    member with no medial curve (kept) is a face like any other: the runs of members
    between such faces are chains of their own (a run of one is a plain fillet)."""
    by_face = {s.face: s for s in blends.fillets}
    # linked sets that are no open chain (closed, branching, ending on blends) are left to
    # the riders' rules (:func:`_bridges`, :func:`_readmit_riders`)
    chains, _ = find_chains(by_face)
    for ch in chains:
        runs: list[list[int]] = [[]]
        for i in range(len(ch.members)):
            if ch.members[i] in job.medials:
                runs[-1].append(i)
            elif runs[-1]:
                runs.append([])
        for run in runs:
            if len(run) < 2:
                continue
            i, j = run[0], run[-1]
            ends = (ch.toward(i, 0), ch.toward(j, 1))
            job.chains.append(
                Chain(tuple(ch.members[k] for k in run), ends, tuple(ch.specs[k] for k in run))
            )
    for ch in job.chains:
        for f, g in zip(ch.members[:-1], ch.members[1:], strict=True):
            job.chain_links |= {(f, g), (g, f)}


def _bridges(job: _Job, blends: BlendInput) -> None:
    """Bridges of the fillets that ride on another fillet with a medial curve (see
    :mod:`.bridge`) into ``job.bridges``; a rider without one is kept."""
    by_face = {s.face: s for s in blends.fillets}
    for spec in blends.fillets:
        for base, e in zip(spec.supporting, spec.smooth_edges, strict=True):
            if spec.face not in job.medials or base not in job.medials:
                continue
            if (spec.face, base) in job.chain_links:  # next in a chain: no bridge
                continue
            supports = tuple(job.face(s) for s in by_face[base].supporting)
            r = bridge_edge(
                job.face(spec.face),
                job.medials[spec.face],
                job.medials[base],
                TopoDS.Edge(job.emap.FindKey(e + 1)),
                (supports[0], supports[1]),
                job.btol,
            )
            if isinstance(r, str):
                why = f"rides on fillet {base}: {r}"
                job.unbridged[spec.face] = (base, job.medials.pop(spec.face), why)
                job.kept[spec.face] = why
                break
            job.bridges[(spec.face, base)] = r[0]


def _readmit_riders(job: _Job, blends: BlendInput) -> None:
    """Riders kept for want of a bridge (:func:`_bridges`) whose base fillet is kept anyway
    are tried as plain fillets: the base is then a supporting face like any other, and the
    rider's half on it merges into it (a torus round a kept cylindrical fillet: an exact
    revolution). When that costs as many fillets that went before as it gains (a fitted
    face that no longer fits with the new halves), nothing changes; all riders are tried
    at once, then (when that does not pay) each alone."""
    by_face = {s.face: s for s in blends.fillets}
    back = {
        r: (base, m, why)
        for r, (base, m, why) in job.unbridged.items()
        if job.kept.get(r) == why and base not in job.specs and base not in job.whole
    }
    if not back:
        return
    if _try_riders(job, by_face, back):
        return
    for r in sorted(back)[:MAX_RIDER_TRIES]:  # all at once cost fillets: each on its own
        _try_riders(job, by_face, {r: back[r]})


def _try_riders(
    job: _Job, by_face: dict[int, FilletSpec], back: dict[int, tuple[int, Medial, str]]
) -> bool:
    """Riders ``back`` tried as plain fillets (see :func:`_readmit_riders`); False, with
    nothing changed, when that costs as many fillets that went before as it gains (a
    fitted face that no longer fits with the new halves)."""
    before: tuple[dict[int, Any], ...] = (
        dict(job.specs),
        dict(job.kept),
        dict(job.surfaces),
        dict(job.no_surface),
    )
    for r, (_, m, _) in back.items():
        job.medials[r] = m
        job.specs[r] = by_face[r]
        job.kept.pop(r)
    _refresh_surfaces(job)
    if any(v == FITTED for v in job.surfaces.values()):
        _fit_pass(job)
    lost = sorted(f for f in before[0] if f not in job.specs)
    gained = [r for r in back if r in job.specs]
    if lost and len(gained) <= len(lost):
        state: tuple[dict[int, Any], ...] = (job.specs, job.kept, job.surfaces, job.no_surface)
        for now, old in zip(state, before, strict=True):
            now.clear()  # in place: the caller holds ``job.kept``
            now.update(old)
        for r, (_, _, why) in back.items():
            job.medials.pop(r)
            job.kept[r] = f"{why}; as a plain fillet on it (it is kept) fillets {lost[:5]} fail"
        return False
    for r, (base, _, why) in back.items():
        if r in job.kept:
            job.kept[r] = f"{why}; as a plain fillet on it (it is kept): {job.kept[r]}"
        else:
            job.say(f"fillet {r} merged into fillet {base}, which is kept (no bridge over it)")
    return True


def _cascade(  # type: ignore[no-untyped-def]
    specs: dict[int, FilletSpec], corners: dict[int, CornerSpec], kept, chains: list[Chain]
) -> None:
    """A corner blend goes only with all its fillets, and a fillet only with its corners;
    a chain of fillets goes whole or not at all: drop until nothing changes."""
    changed = True
    while changed:
        changed = False
        for ch in chains:
            gone = [f for f in ch.members if f not in specs]
            if gone and len(gone) < len(ch.members):
                for f in ch.members:
                    if f in specs:
                        specs.pop(f)
                        kept.setdefault(
                            f, f"in a chain of tangent fillets with fillet {gone[0]}, which is kept"
                        )
                changed = True
        for c, cs in list(corners.items()):
            gone = [f for f in cs.fillets if f not in specs]
            if gone:
                corners.pop(c)
                kept.setdefault(c, f"corner blend: fillet {gone[0]} meeting it is kept")
                for f in cs.fillets:
                    if f in specs:
                        specs.pop(f)
                        kept.setdefault(f, f"meets corner blend {c}, which is kept")
                changed = True


def _refresh_surfaces(job: _Job) -> None:
    """Merged surface per supporting face into ``job.surfaces``: an exact one, or
    ``FITTED`` for a plane whose pieces have none (fitted per attempt); fillets of other
    faces move to ``job.kept``. Exact surfaces depend on which halves a face gets, so this
    runs again whenever fillets are dropped."""
    specs, kept = job.specs, job.kept
    while True:
        _cascade(specs, job.corners, kept, job.chains)
        surfaces, failed = _surfaces_for(job, specs, job.corners)
        if not failed:
            job.surfaces = surfaces
            return
        for f, (sup, why) in failed.items():
            if f not in kept:
                kept[f] = why
                job.no_surface[f] = sup
            specs.pop(f, None)


def _surfaces_for(
    job: _Job, specs: dict[int, FilletSpec], corners: dict[int, CornerSpec]
) -> tuple[dict[int, MergedSurface | str], dict[int, tuple[int, str]]]:
    """The merged surface of every supporting face for the fillets ``specs`` and corner
    blends ``corners`` (``FITTED`` where a fitted route serves), and the fillets of the
    first face that has none, each with that face and the reason (empty when every face
    has one)."""
    with_corner = {s for cs in corners.values() for s in cs.supporting}
    with_corner |= {
        s
        for base, rs in riders(specs).items()
        if any((r, base) not in job.chain_links for r in rs)
        for s in specs[base].supporting
    }
    surfaces: dict[int, MergedSurface | str] = {}
    for sup, hs in halves_of(specs).items():
        if sup in specs:  # a simplified fillet: its riders' pieces go to its supports
            continue
        # a fillet merged whole (see :func:`_one_sided`) has the same (fillet, edge) as its
        # half: the medial parameter tells them apart
        key = (sup, sup in with_corner, *sorted((f, e, job.medials[f].mid) for f, e in hs))
        if key not in job.exact:
            job.exact[key] = _surface_of(job, sup, hs, sup in with_corner)
        ms = job.exact[key]
        if isinstance(ms, str) and ms != FITTED:
            return surfaces, {f: (sup, f"supporting face {sup}: {ms}") for f, _ in hs}
        surfaces[sup] = ms
    return surfaces, {}


def _surface_of(
    job: _Job, sup: int, hs: list[tuple[int, int]], with_corner: bool
) -> MergedSurface | str:
    """The merged surface of supporting face ``sup`` with the halves ``hs`` ((fillet, smooth
    edge) pairs): exact, ``FITTED``, or the reason there is none."""
    support = job.face(sup)
    planar = BRepAdaptor_Surface(support).GetType() == GeomAbs_Plane
    if with_corner:
        return FITTED if planar else "corner or bridged pieces on a curved face"
    halves = []
    for f, e in hs:
        half = Half(job.face(f), job.medials[f], TopoDS.Edge(job.emap.FindKey(e + 1)))
        ch = next((c for c in job.chains if sup in c.ends and f in c.members), None)
        if ch is not None:
            end = ch.ends.index(sup)
            faces = [job.face(g) for g in ch.members]
            arcs = chain_arcs(ch, end, faces, job.medials)
            if isinstance(arcs, str):
                return arcs
            others = [
                job.face(g)
                for i, g in enumerate(ch.members)
                if g != f and (ch.side(i) == end or i == ch.middle)
            ]
            half = replace(half, chain=tuple(others), arcs=tuple(arcs))
        halves.append(half)
    try:
        ms = merged_surface(support, halves, job.btol)
    except (ValueError, RuntimeError) as err:  # OCCT construction failures
        ms = f"surface construction failed: {err}"
    if isinstance(ms, str) and (planar or _ring_kind(support) or _graph_kind(support)):
        return FITTED
    if isinstance(ms, str):
        kind = str(BRepAdaptor_Surface(support).GetType()).split("_")[-1].lower()
        return (
            f"{ms}; the fitted routes take planar and cylindrical supporting faces "
            f"only (this one is a {kind})"
        )
    return ms


def _one_sided(job: _Job, blends: BlendInput) -> None:
    """Fillets kept because one supporting face has no surface for their half are merged
    whole into the other supporting face, where that face then has an exact surface (an
    extrusion or revolution whose profile runs across the whole fillet): the face that had
    none is left as it was (or fitted without this fillet, when the fillet's own piece held
    its misfit: a fillet ending at a step, where a rib ends on a plate), the fillet still
    goes and the shape is the same. Not for
    fillets meeting corner blends, riding on or ridden by fillets, or traced ones."""
    by_face = {s.face: s for s in blends.fillets}
    linked = {f for cs in blends.corners for f in cs.fillets}
    linked |= {b for s in blends.fillets for b in s.supporting if b in by_face}
    linked |= {s.face for s in blends.fillets if set(s.supporting) & set(by_face)}
    for f, why in sorted(job.kept.items()):
        bad = job.no_surface.get(f)
        spec, m = by_face.get(f), job.medials.get(f)
        if bad is None or spec is None or m is None or f in linked or m.iso == TRACED:
            continue
        if bad not in spec.supporting:
            continue
        if f not in job.own_misfit and any(bad in s.supporting for s in job.specs.values()):
            continue  # the failing face keeps other fillets' halves: it is tried with them
        k = 1 - spec.supporting.index(bad)  # the side whose face takes the whole fillet
        if not abs(m.cross[1 - k]) < 1e99:  # OCCT's "infinite": the far edge did not project
            continue
        whole = replace(
            spec, smooth_edges=(spec.smooth_edges[k],), supporting=(spec.supporting[k],)
        )
        trial = {**job.specs, f: whole}
        job.medials[f] = replace(m, mid=m.cross[1 - k])  # the profile runs to the far edge
        surfaces, failed = _surfaces_for(job, trial, job.corners)
        if failed or not isinstance(surfaces.get(spec.supporting[k]), MergedSurface):
            job.medials[f] = m
            continue
        job.specs, job.surfaces = trial, surfaces
        job.whole[f] = spec.supporting[k]
        job.kept.pop(f)
        job.say(f"fillet {f} merged whole into face {spec.supporting[k]} ({why[:60]}...)")


def _fitted(job: _Job, split: Any, g: Group, probe: bool = False) -> FittedSurface | str:
    """The fitted surface of group ``g`` (cached by its support and its members' origins);
    with ``probe`` the cheap height-field check only (see :func:`graph_surface`)."""
    assert g.support is not None
    key = (int(probe), g.support, *sorted(split.origin[k] for k in g.members))
    if job.cylinder_field and _ring_kind(job.face(g.support)):
        key = (-1, *key)  # (the first pass's ring refusal is no answer now)
    if key not in job.cache:
        members = [TopoDS.Face(split.face_map.FindKey(k + 1)) for k in g.members]
        fit_tol = FIT_SHARE * job.tol * job.diag
        accept = ACCEPT_SHARE * job.tol * job.diag
        support = job.face(g.support)
        try:
            # the ring route first (one blend half all the way round a boss or a hole:
            # planes and cylinders), else the height field over a plane, or over the
            # cylinder (any blend halves on any part of it)
            ring = ring_surface(support, members, fit_tol, job.btol, probe, accept)
            if isinstance(ring, str) and not _ring_kind(support):
                # (the probe's setup and fit serve the full fit of the same group)
                skey = key[1:]
                if skey not in job.setups:
                    job.setups[skey] = graph_setup(support, members, job.btol)
                setup = job.setups[skey]
                flat = graph_surface(support, members, fit_tol, job.btol, probe, setup, accept)
                if isinstance(flat, str) and _ring_applies(ring):
                    flat = Refusal(f"{flat}; ring route: {ring}", _culprits_of(flat))
                job.cache[key] = flat
            elif isinstance(ring, str) and job.cylinder_field:
                # a cylinder the ring route refused: the field over the cylinder
                cyl = cylinder_surface(support, members, fit_tol, job.btol, probe, accept)
                if isinstance(cyl, str) and _ring_applies(ring):
                    cyl = f"{cyl}; ring route: {ring}"
                job.cache[key] = cyl
            else:
                job.cache[key] = ring
        except Exception as err:  # OCCT failures while sampling the pieces
            job.cache[key] = f"fitting failed ({type(err).__name__}: {err})"
    return job.cache[key]


def _ring_kind(face: Any) -> bool:
    """Whether a supporting face takes the ring route and then the field over its
    cylinder, not the height field over a plane (a cylinder: see :mod:`.ring`,
    :mod:`.cylinder_field`)."""
    return BRepAdaptor_Surface(face).GetType() == GeomAbs_Cylinder


def _graph_kind(face: Any) -> bool:
    """Whether a curved supporting face may take the height-field route (over its mean
    plane): any surface but a cylinder (ring route) that converts to a B-spline; the fit
    itself refuses a merged face that is no graph."""
    return BRepAdaptor_Surface(face).GetType() not in (GeomAbs_Plane, GeomAbs_Cylinder)


def _ring_applies(why: str) -> bool:
    """Whether the ring route's refusal ``why`` came after the group looked like a ring (a
    fit that missed, a pole on the face; not a group of another shape): worth naming next
    to the planar route's reason."""
    return not why.startswith(NOT_A_RING)


def _split(
    job: _Job, sel: dict[int, FilletSpec], csel: dict[int, CornerSpec], keep: bool = False
) -> Any:
    """The working solid split along the medial curves of ``sel`` and the arcs of ``csel``,
    and its groups. The split a fit round kept (``keep``) is taken again by the next call
    when it was made with the same tool edges (the fit rounds only read it; an attempt,
    whose rebuild adds pcurves to its edges, takes it and leaves none behind)."""
    whole = {f for ch in job.chains for i, f in enumerate(ch.members) if i != ch.middle} | set(
        job.whole
    )
    tools = [job.medials[f].edge for f in sel if f not in whole]
    tools += [e for c in csel for e in job.arcs[c]]
    tools += [e for (f, base), e in job.bridges.items() if f in sel and base in sel]
    last, job.last_split = job.last_split, None
    same = last is not None and len(last[0]) == len(tools)
    if last is not None and same and all(a.IsSame(b) for a, b in zip(last[0], tools, strict=True)):
        split = last[1]
    else:
        split = split_along(job.work, tools)
    if keep:
        job.last_split = (tools, split)
    groups = build_groups(
        split,
        {f: s.supporting for f, s in sel.items()},
        {c: cs.supporting for c, cs in csel.items()},
    )
    return split, groups


def _fit_pass(job: _Job) -> None:
    """Check every fitted face on the full split, first cheaply (is it a height field at
    all?) until no face fails, then with the full fit; fillets of faces that fail are kept
    (with the reason) before the rebuild is tried, so bisection is not spent on them; so are
    fillets that a group on the full split cannot be formed with (:class:`GroupError`).
    Where a face's misfit is traced to some of its blends, only those are kept and the face
    is fitted again (each round keeps at least one blend, so the rounds end)."""
    for probe in (True, False):
        for _ in range(len(job.specs) + len(job.corners) + 1):
            if not _fit_round(job, probe):
                break
            _refresh_surfaces(job)


def _fit_round(job: _Job, probe: bool) -> bool:
    """One round of :func:`_fit_pass`; True when some face failed (and was dropped)."""
    fitted = {s for s, v in job.surfaces.items() if v == FITTED}
    if not fitted or not job.specs:
        return False
    try:
        split, groups = _split(job, job.specs, job.corners, keep=True)
    except GroupError as err:  # traced to fillets: keep them now, not after a search
        blamed = {f for c in err.faces if c in job.corners for f in job.corners[c].fillets}
        blamed |= err.faces & set(job.specs)
        if not blamed:
            return False
        job.say(f"fillets {sorted(blamed)} kept: {err}")
        for f in blamed:
            job.specs.pop(f, None)
            job.kept.setdefault(f, f"rebuild failed: {err}")
        _cascade(job.specs, job.corners, job.kept, job.chains)
        return True
    except CadError:
        return False  # the attempt will report it
    bad: dict[int, str] = {}
    traced: dict[int, set[int]] = {}  # support -> the blends its misfit is traced to
    for g in groups:
        if g.support is not None and g.support in fitted:
            r = _fitted(job, split, g, probe)
            if isinstance(r, str):
                bad[g.support] = r
                traced[g.support] = {
                    split.origin[g.members[i]] for i in _culprits_of(r) if i < len(g.members)
                } & (set(job.specs) | set(job.corners))
    if not bad:
        return False
    job.say(f"fitted surfaces failed on faces {sorted(bad)}")
    for sup, why in bad.items():
        culprits = traced[sup]
        if culprits:  # the misfit lies on these blends' pieces: the others are tried again
            _keep_culprits(job, sup, why, culprits)
            continue
        # else the second pass's newcomers first (:func:`_cylinder_pass`), or a chain of
        # fillets ending on the face, alone (it goes whole or not at all, and its pieces are
        # the likeliest to spoil the fit): the face's other fillets are tried again without
        # them in the next round
        mine = [f for f, s in job.specs.items() if sup in s.supporting]
        first = [f for f in mine if f in job.prefer]
        if not first:
            chained = {f for ch in job.chains if sup in ch.ends for f in ch.members}
            first = [f for f in mine if f in chained]
        for f in first or mine:
            if f in job.specs:
                job.specs.pop(f)
                if f not in job.kept:
                    job.kept[f] = f"supporting face {sup}: {why}"
                    job.no_surface[f] = sup
    _cascade(job.specs, job.corners, job.kept, job.chains)
    return True


def _culprits_of(why: str) -> frozenset[int]:
    """The members a fitted route's refusal is traced to (none for a plain reason)."""
    return why.culprits if isinstance(why, Refusal) else frozenset()


def _keep_culprits(job: _Job, sup: int, why: str, culprits: set[int]) -> None:
    """Keep the fillets and corner blends ``culprits`` whose pieces hold the misfit of
    supporting face ``sup`` (reason ``why``); the other fillets of ``sup`` stay in."""
    job.say(f"face {sup}: the misfit lies on blends {sorted(culprits)}; they are kept")
    for f in sorted(culprits):
        reason = f"supporting face {sup}: {why} (on this blend's piece)"
        if f in job.corners:
            job.corners.pop(f)
            job.kept.setdefault(f, reason)
        elif f in job.specs:
            job.specs.pop(f)
            if f not in job.kept:
                job.kept[f] = reason
                job.no_surface[f] = sup
                job.own_misfit.add(f)


def _cylinder_pass(job: _Job, tried: dict[int, FilletSpec], corners: dict[int, CornerSpec]) -> bool:
    """The fillets the fit pass kept because the ring route refused a cylinder of theirs
    (``tried``: the fillets before the pass), tried again with the cylinder field
    (:mod:`.cylinder_field`). A face whose fit then fails drops these newcomers first
    (``job.prefer``): their halves can spoil a face that fitted without them (a plate
    whose circles round the bosses come off the knot lines), and the fillets merged
    there before stay merged. Not for fillets meeting a corner blend that was split before
    the pass (``corners``: it goes only with all its fillets, and is kept now). True when
    some fillet was tried."""
    job.cylinder_field = True
    linked = {f for cs in corners.values() for f in cs.fillets}
    cands = {
        f
        for f, sup in job.no_surface.items()
        if f in tried and f in job.kept and f not in linked and f not in job.specs
        and _ring_kind(job.face(sup))
    }  # fmt: skip
    if not cands:
        return False
    job.say(f"{len(cands)} fillets kept at cylinders tried with the cylinder field")
    old = {f: (job.kept.pop(f), job.no_surface.pop(f)) for f in cands}
    job.specs.update({f: tried[f] for f in cands})
    job.prefer = set(cands)
    _refresh_surfaces(job)
    _fit_pass(job)
    job.prefer = set()
    for f in cands:
        if f not in job.specs and f not in job.kept:  # (dropped without a reason of its own)
            job.kept[f], job.no_surface[f] = old[f]
    return True


def _attempt(job: _Job, sel: dict[int, FilletSpec]) -> _Attempt | str:
    """Split, merge and rebuild with the fillets ``sel`` (and the corners all of whose
    fillets are in it), then validate; the reason (str) when any step or check fails."""
    csel = {c: cs for c, cs in job.corners.items() if set(cs.fillets) <= set(sel)}
    fit_err = 0.0
    surfaces, failed = _surfaces_for(job, sel, csel)
    if failed:
        return Failure(next(iter(failed.values()))[1], failed)
    try:
        job.say(f"splitting {len(sel)} fillets and {len(csel)} corner blends along medial curves")
        split, groups = _split(job, sel, csel)
        used: dict[int, Any] = {}
        fitted_dv = 0.0
        for g in groups:
            if g.support is None:
                continue
            ms = surfaces[g.support]
            if isinstance(ms, str):
                fs = _fitted(job, split, g)
                if isinstance(fs, str):
                    return Failure(f"face {g.support}: {fs}", _fillets_of(split, [g], sel))
                used[g.support] = fs.surface
                fit_err = max(fit_err, fs.error)
                fitted_dv += fs.volume_change
            else:
                used[g.support] = ms.surface
        expected = fitted_dv / job.vol_ref if fit_err > 0 else None
        job.say(f"rebuilding: {len(groups)} faces")
        shape, faces = build_solid(split, groups, used, job.btol)
    except GroupError as err:  # traced to faces: blame their fillets (a corner's, its own)
        blamed = {f for c in err.faces if c in csel for f in csel[c].fillets}
        return Failure(str(err), blamed | (err.faces & set(sel)))
    except CadError as err:
        return str(err)
    except Exception as err:  # OCCT Standard_Failure subclasses, translated here
        return f"OCCT failed while rebuilding ({type(err).__name__}: {err})"
    try:
        checked = _validated(job, split, groups, faces, shape, surfaces, expected, sel)
    except Exception as err:  # OCCT failures while measuring: the solid is not accepted
        return f"OCCT failed while validating ({type(err).__name__}: {err})"
    if isinstance(checked, str):
        return checked
    dv, da, dev, kinds, base = checked
    halves_origin = {g.id: [split.origin[k] for k in g.halves] for g in groups}
    return _Attempt(
        shape,
        groups,
        faces,
        dev,
        base * (1 + dv),
        split.origin,
        halves_origin,
        kinds,
        fit_err,
        expected or 0.0,
        da,
        base,
    )


def _fillets_of(split: Any, groups: list[Group], sel: dict[int, FilletSpec]) -> set[int]:
    """The fillets of ``sel`` with a half (or the whole) in one of ``groups``."""
    return {split.origin[k] for g in groups for k in g.halves} & set(sel)


def _validated(
    job: _Job,
    split: Any,
    groups: list[Group],
    faces: list[Any],
    shape: Any,
    surfaces: dict[int, MergedSurface | str],
    expected: float | None,
    sel: dict[int, FilletSpec],
) -> tuple[float, float, float, dict[int, str], float] | str:
    """The checks of a rebuilt ``shape`` with the fillets ``sel``: (relative volume change,
    relative area change, largest deviation, surface kind per group, the input's volume the
    change is relative to), or the reason it fails
    (a :class:`.search.Failure` naming the fillets of the new faces that failed their own
    check: validity, free edges, deviation; volume and area are the whole solid's)."""
    diag, tol = job.diag, job.tol
    job.say("validating (analyzer, shell, volume, area, deviation both ways)")
    merged = [(g, f) for g, f in zip(groups, faces, strict=True) if g.support is not None]
    c = check(shape, with_volume=False)
    if not c.valid:
        bad = [g for g, f in merged if not BRepCheck_Analyzer(f).IsValid()]
        return Failure("rebuilt solid not valid (BRepCheck_Analyzer)", _fillets_of(split, bad, sel))
    shells = count(job.work, TopAbs_SHELL)  # an outer shell and one per cavity
    if c.shells != shells or not c.closed:
        open_faces = free_edge_faces(shape)
        bad = [g for g, f in merged if any(f.IsSame(o) for o in open_faces)]
        return Failure(
            f"rebuilt solid has {c.shells} shells (the input {shells}) / free edges",
            _fillets_of(split, bad, sel),
        )
    dev = 0.0
    kinds: dict[int, str] = {}
    far: list[Group] = []
    for i, (g, face) in enumerate(merged):
        log_progress(log, "validation: deviation sampled on merged faces", i + 1, len(merged))
        assert g.support is not None
        ms = surfaces[g.support]
        kinds[g.id] = FITTED if isinstance(ms, str) else ms.kind
        n = FITTED_DEVIATION_SAMPLES if isinstance(ms, str) else DEVIATION_SAMPLES
        old = [TopoDS.Face(split.face_map.FindKey(k + 1)) for k in g.members]
        d = max(deviation(old, face, n=n, enough=1e-3 * tol * diag))
        if d > tol * diag:
            far.append(g)
        dev = max(dev, d)
    if far:
        return Failure(
            f"surface deviation {dev / diag:.2e} x diagonal (> {tol:g})",
            _fillets_of(split, far, sel),
        )
    # volume and area: on the changed faces when that settles it, else on the whole solid
    changed = [(g, f) for g, f in zip(groups, faces, strict=True) if not g.untouched]
    new = [f for _, f in changed]
    old = [TopoDS.Face(split.face_map.FindKey(k + 1)) for g, _ in changed for k in g.members]
    shares = contributions(new, old, job.vol_ref, VOLUME_TOL)
    owner = list(range(len(changed))) + [i for i, (g, _) in enumerate(changed) for _ in g.members]
    per_group = np.bincount(owner, weights=shares, minlength=len(changed))

    def refused(why: str, dv: float) -> Failure:
        """The volume refusal, blamed on the groups that account for the change (the
        change is the whole attempt's: a fillet tried with accepted ones shares it)."""
        picked = volume_blame(per_group, dv, VOLUME_TOL)
        fillets = _fillets_of(split, [changed[i][0] for i in picked], sel)
        if fillets:
            names = ", ".join(map(str, sorted(fillets)[:5])) + (", ..." if len(fillets) > 5 else "")
            why += f"; {float(per_group[picked].sum()):.1e} of it on the faces of fillets {names}"
        return Failure(why, fillets)

    dv_local = local_volume_change(new, old, job.vol_ref, VOLUME_TOL, expected, shares)
    base = job.vol_ref  # the volume the change is relative to
    if dv_local is None:
        base = job.vol0
        dv, why = volume_change(shape, base, VOLUME_TOL, expected)
        if why:
            return refused(why, dv)
    elif abs(dv_local) > VOLUME_TOL:  # two integrators agree on the changed faces
        return refused(f"volume changed by {abs(dv_local):.2e} (> {VOLUME_TOL:g})", dv_local)
    else:
        dv = dv_local
    if job.area0 is None:
        job.area0 = area(job.work)
    da_local = local_area_change(new, old, job.area0, AREA_TOL)
    if da_local is None:
        da, why = area_change(shape, job.area0, AREA_TOL)
        if why:
            return why
    else:
        da = da_local
    return dv, da, dev, kinds, base


def _identity_groups(n: int) -> list[FaceGroup]:
    return [FaceGroup(i, (i,), (), "original") for i in range(n)]


def _face_groups(a: _Attempt) -> list[FaceGroup]:
    fmap = shape_map(a.shape, TopAbs_FACE)
    out = []
    for g, face in zip(a.groups, a.faces, strict=True):
        idx = fmap.FindIndex(face) - 1
        halves = set(a.halves_origin[g.id])
        whole = sorted({a.origin[k] for k in g.members} - halves)
        out.append(
            FaceGroup(idx, tuple(whole), tuple(sorted(halves)), a.kinds.get(g.id, "original"))
        )
    return sorted(out, key=lambda g: g.new_face)
