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
from typing import Any

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy
from OCP.GeomAbs import GeomAbs_Sphere
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopoDS import TopoDS

from medax._progress import log_progress
from medax.cad.simplify.attempt_checks import fillets_of, validated
from medax.cad.simplify.bridge import bridge_edge
from medax.cad.simplify.chains import chain_specs, find_chains, sub_chains
from medax.cad.simplify.corner import corner_arcs, corner_sections, plane_normal
from medax.cad.simplify.groups import Group, GroupError
from medax.cad.simplify.job import (
    ACCEPT_SHARE,
    AREA_TOL,
    BUILD_TOL,
    DEVIATION_TOL,
    FIT_SHARE,
    FITTED,
    ISOLATION_BUDGET,
    MAX_RIDER_TRIES,
    RUN_BUDGET,
    SECOND_PASS_BUDGET,
    VOLUME_TOL,
    Attempt,
    Job,
)
from medax.cad.simplify.medial import AXIS, Medial, medial_curve
from medax.cad.simplify.merging import (
    cascade,
    cylinder_pass,
    fit_pass,
    fitted_surface,
    one_sided,
    refresh_surfaces,
    split_job,
    surfaces_for,
)
from medax.cad.simplify.mitre import mitre_keeps, mitre_pairs
from medax.cad.simplify.occ import count, diagonal, shape_map, xyz
from medax.cad.simplify.rebuild import build_solid
from medax.cad.simplify.result import FaceGroup, SimplifyResult
from medax.cad.simplify.rounded import ROUNDED, RoundedSurface
from medax.cad.simplify.search import Failure, isolate
from medax.cad.simplify.specs import BlendInput, FilletSpec
from medax.cad.simplify.surfaces import MergedSurface
from medax.cad.simplify.validate import (
    check,
    default_volume,
)
from medax.errors import CadError

__all__ = [
    "ACCEPT_SHARE",
    "AREA_TOL",
    "BUILD_TOL",
    "DEVIATION_TOL",
    "FIT_SHARE",
    "FaceGroup",
    "ISOLATION_BUDGET",
    "SimplifyResult",
    "VOLUME_TOL",
    "simplify",
]

log = logging.getLogger(__name__)


def simplify(
    shape: Any,
    blends: BlendInput,
    tol: float = DEVIATION_TOL,
    progress: Callable[[str], None] | None = None,
    time_budget: float = ISOLATION_BUDGET,
    strict_volume: bool = False,
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
        CPU seconds the search for the failing fillets may take when the rebuild with all of
        them fails; fillets not tried by then are kept, with that reason. The search also
        stops starting attempts when one more, as long as the first, would end after
        ``RUN_BUDGET`` (480 s) of the whole run. Budgets count this process's CPU time, so the
        result does not depend on the machine's load.
    strict_volume : bool
        Also keep the fillets whose merged faces OCCT's default mass properties (FreeCAD,
        CadQuery) would read as a volume change above ``VOLUME_TOL``: its fixed Gauss rules
        do not resolve the curvature jumps inside a merged face (a fillet half meeting its
        plane), so fitted faces read 1e-5 - 1e-2 of the volume off there.

    Returns
    -------
    SimplifyResult
        The validated solid and what was removed and kept.
    """
    t0, w0 = time.process_time(), time.perf_counter()
    say = progress or (lambda msg: log.info(msg))
    work = BRepBuilderAPI_Copy(shape, True, False).Shape()
    fmap = shape_map(work, TopAbs_FACE)
    job = Job(
        work,
        fmap,
        shape_map(work, TopAbs_EDGE),
        diagonal(work),
        tol,
        say,
        dict(blends.refused),
        strict_volume=strict_volume,
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
    _unlinked_axes(job, blends)
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
    cascade(job.specs, job.corners, kept, job.chains)
    refresh_surfaces(job)
    n_fit = sum(1 for v in job.surfaces.values() if v == FITTED)
    say(f"{len(job.specs)} fillets on {len(job.surfaces)} merged faces ({n_fit} fitted)")

    def attempt(sel: dict[int, FilletSpec]) -> Attempt | str:
        return _attempt(job, sel)

    before_fit, corners_before = dict(job.specs), dict(job.corners)
    if n_fit:
        fit_pass(job)
    one_sided(job, blends)

    def late(what: str) -> bool:
        used = time.process_time() - t0
        if used > SECOND_PASS_BUDGET:
            say(f"{what} not tried: {used:.0f} s of the run's {RUN_BUDGET:.0f} s used")
        return used > SECOND_PASS_BUDGET

    # (after the fillets merged whole: a cylinder's newcomer must not take their place)
    if n_fit and not late("the cylinder field") and cylinder_pass(job, before_fit, corners_before):
        one_sided(job, blends)
    job.cylinder_field = True
    _readmit_riders(job, blends, lambda: late("riders as plain fillets"))
    specs, corners = job.specs, job.corners
    t_first = time.process_time()
    first = attempt(specs) if specs else None
    result: Attempt | None
    if isinstance(first, str):
        say(f"rebuild with all fillets failed ({first}); isolating the failing fillets")
        now = time.process_time()
        deadline = min(now + time_budget, t0 + RUN_BUDGET - (now - t_first))
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
        time_s=time.perf_counter() - w0,
        cpu_s=time.process_time() - t0,
        medial_error=max((job.medials[f].error for f in removed if f in job.medials), default=0.0),
        fit_error=result.fit_error if result is not None else 0.0,
        fit_volume_rel_change=result.fit_dv if result is not None else 0.0,
        area_rel_change=result.area_change if result is not None else 0.0,
        default_volume_rel_change=default_volume(final) / default_volume(shape) - 1.0,
        notes=notes,
        radii={spec.face: spec.radius for spec in blends.fillets},
    )


def _unlinked_axes(job: Job, blends: BlendInput) -> None:
    """Keep the fillets whose medial curve is the paper's axis (:data:`.medial.AXIS`) where
    they are linked to other blends (in a chain, ridden on, riding, at a corner blend):
    the chain, bridge and corner routes need iso-line sections across them, and the
    fillets linked to such a one then go as they go beside a kept fillet."""
    for f in sorted(blends.linked):
        m = job.medials.get(f)
        if m is not None and m.iso == AXIS:
            del job.medials[f]
            job.kept[f] = (
                "smooth edges are not iso-lines of the fillet surface, and it meets other "
                "blends (the chain, bridge and corner routes need an iso-line medial curve)"
            )


def _corners(job: Job, blends: BlendInput) -> None:
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
        corner = job.face(cs.face)
        if BRepAdaptor_Surface(corner).GetType() == GeomAbs_Sphere:
            r = corner_arcs(corner, pairs, normals)
        else:  # a vertex blend between fillets of several radii
            planes = {s: (n, float(n @ _plane_point(job.face(s)))) for s, n in normals.items()}
            medials = [job.medials[f].edge for f in cs.fillets]
            r = corner_sections(corner, pairs, planes, medials, job.btol)
        if isinstance(r, str):
            job.kept[cs.face] = r
            continue
        job.corners[cs.face], job.arcs[cs.face] = cs, r[0]


def _plane_point(face: Any) -> np.ndarray:
    """A point (3,) of the plane of planar ``face``."""
    return xyz(BRepAdaptor_Surface(face).Plane().Location())


def _chains(job: Job, blends: BlendInput) -> None:
    """Chains of tangent fillets (see :mod:`.chains`) into ``job.chains``. A chain
    member with no medial curve (kept) is a face like any other: the runs of members
    between such faces are chains of their own (a run of one is a plain fillet)."""
    by_face = {s.face: s for s in blends.fillets}
    # linked sets that are no open chain (closed, branching, ending on blends) are left to
    # the riders' rules (:func:`_bridges`, :func:`_readmit_riders`)
    chains, _ = find_chains(by_face)
    for ch in chains:
        job.chains += sub_chains(ch, set(job.medials))
    for ch in job.chains:
        for f, g in zip(ch.members[:-1], ch.members[1:], strict=True):
            job.chain_links |= {(f, g), (g, f)}


def _bridges(job: Job, blends: BlendInput) -> None:
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


def _readmit_riders(job: Job, blends: BlendInput, late: Callable[[], bool]) -> None:
    """Riders kept for want of a bridge (:func:`_bridges`) whose base fillet is kept anyway
    are tried as plain fillets: the base is then a supporting face like any other, and the
    rider's half on it merges into it (a torus round a kept cylindrical fillet: an exact
    revolution). When that costs as many fillets that went before as it gains (a fitted
    face that no longer fits with the new halves), nothing changes; all riders are tried
    at once, then (when that does not pay) each alone, while not ``late()``."""
    by_face = {s.face: s for s in blends.fillets}
    back = {
        r: (base, m, why)
        for r, (base, m, why) in job.unbridged.items()
        if job.kept.get(r) == why and base not in job.specs and base not in job.whole
    }
    if not back or late():
        return
    if _try_riders(job, by_face, back):
        return
    for r in sorted(back)[:MAX_RIDER_TRIES]:  # all at once cost fillets: each on its own
        if late():
            return
        _try_riders(job, by_face, {r: back[r]})


def _try_riders(
    job: Job, by_face: dict[int, FilletSpec], back: dict[int, tuple[int, Medial, str]]
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
    refresh_surfaces(job)
    if any(v == FITTED for v in job.surfaces.values()):
        fit_pass(job)
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


def _attempt(job: Job, sel: dict[int, FilletSpec]) -> Attempt | str:
    """Split, merge and rebuild with the fillets ``sel`` (and the corners all of whose
    fillets are in it), then validate; the reason (str) when any step or check fails."""
    csel = {c: cs for c, cs in job.corners.items() if set(cs.fillets) <= set(sel)}
    fit_err = 0.0
    surfaces, failed = surfaces_for(job, sel, csel)
    if failed:
        return Failure(next(iter(failed.values()))[1], failed)
    try:
        job.say(f"splitting {len(sel)} fillets and {len(csel)} corner blends along medial curves")
        split, groups = split_job(job, sel, csel)
        used: dict[int, Any] = {}
        fitted_dv = 0.0
        for g in groups:
            if g.support is None:
                continue
            ms = surfaces[g.support]
            if isinstance(ms, str):
                fs = fitted_surface(job, split, g)
                if isinstance(fs, str):
                    return Failure(f"face {g.support}: {fs}", fillets_of(split, [g], sel))
                used[g.support] = fs.surface
                if isinstance(fs, RoundedSurface):  # exact: checked as the exact ones are
                    surfaces[g.support] = MergedSurface(fs.surface, ROUNDED, None)
                fit_err = max(fit_err, fs.error)
                fitted_dv += fs.volume_change
            else:
                used[g.support] = ms.surface
        expected = fitted_dv / job.vol_ref if fit_err > 0 else None
        job.say(f"rebuilding: {len(groups)} faces")
        pieces = _pieces_before(split, groups)
        shape, faces = build_solid(split, groups, used, job.btol, job.pcurves)
    except GroupError as err:  # traced to faces: blame their fillets (a corner's, its own)
        blamed = {f for c in err.faces if c in csel for f in csel[c].fillets}
        return Failure(str(err), blamed | (err.faces & set(sel)))
    except CadError as err:
        return str(err)
    except Exception as err:  # OCCT Standard_Failure subclasses, translated here
        return f"OCCT failed while rebuilding ({type(err).__name__}: {err})"
    try:
        checked = validated(job, split, groups, faces, shape, surfaces, expected, sel, pieces)
    except Exception as err:  # OCCT failures while measuring: the solid is not accepted
        return f"OCCT failed while validating ({type(err).__name__}: {err})"
    if isinstance(checked, str):
        return checked
    dv, da, dev, kinds, base = checked
    halves_origin = {g.id: [split.origin[k] for k in g.halves] for g in groups}
    return Attempt(
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


def _pieces_before(split: Any, groups: list[Group]) -> dict[int, Any]:
    """The split's pieces of the changed groups (split face index -> face), copied with
    their geometry before the rebuild. A merged face on a support's own surface shares
    that surface's handle, so its edges share their pcurves with the old pieces, and the
    healing of the rebuild changes them in place (seen: on a cylinder, five pcurves moved
    by one period, and the old piece's share of the volume went 18913 -> -11256); the
    checks compare the new faces with these copies."""
    return {
        k: TopoDS.Face(BRepBuilderAPI_Copy(split.face_map.FindKey(k + 1), True, False).Shape())
        for g in groups
        if not g.untouched
        for k in g.members
    }


def _identity_groups(n: int) -> list[FaceGroup]:
    return [FaceGroup(i, (i,), (), "original") for i in range(n)]


def _face_groups(a: Attempt) -> list[FaceGroup]:
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
