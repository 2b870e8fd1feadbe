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
from functools import partial
from typing import Any

import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.GeomAbs import GeomAbs_Sphere
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_SHELL
from OCP.TopoDS import TopoDS

from medax._progress import log_progress
from medax.cad.simplify.bridge import bridge_edge
from medax.cad.simplify.chains import chain_specs, find_chains, sub_chains
from medax.cad.simplify.corner import corner_arcs, corner_sections, plane_normal
from medax.cad.simplify.gap_measure import gap_volume
from medax.cad.simplify.groups import Group, GroupError
from medax.cad.simplify.job import (
    ACCEPT_SHARE,
    AREA_TOL,
    BUILD_TOL,
    DEVIATION_TOL,
    FIT_SHARE,
    FITTED,
    FITTED_DEVIATION_SAMPLES,
    ISOLATION_BUDGET,
    MAX_RIDER_TRIES,
    RUN_BUDGET,
    SECOND_PASS_BUDGET,
    VOLUME_TOL,
    Attempt,
    Job,
)
from medax.cad.simplify.local_measure import (
    area_delta,
    component_origins,
    contributions,
    default_reading,
    group_key,
    local_area_change,
    local_volume_shares,
    rough_centre,
    tolerance_band,
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
from medax.cad.simplify.result import DEVIATION_SAMPLES, FaceGroup, SimplifyResult
from medax.cad.simplify.rounded import ROUNDED, RoundedSurface
from medax.cad.simplify.search import Failure, isolate, volume_blame
from medax.cad.simplify.specs import BlendInput, FilletSpec
from medax.cad.simplify.surfaces import MergedSurface
from medax.cad.simplify.validate import (
    area,
    area_change,
    check,
    default_volume,
    deviation,
    free_edge_faces,
    volume_change,
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
                    return Failure(f"face {g.support}: {fs}", _fillets_of(split, [g], sel))
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
        checked = _validated(job, split, groups, faces, shape, surfaces, expected, sel, pieces)
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


def _fillets_of(split: Any, groups: list[Group], sel: dict[int, FilletSpec]) -> set[int]:
    """The fillets of ``sel`` with a half (or the whole) in one of ``groups``."""
    return {split.origin[k] for g in groups for k in g.halves} & set(sel)


def _validated(
    job: Job,
    split: Any,
    groups: list[Group],
    faces: list[Any],
    shape: Any,
    surfaces: dict[int, MergedSurface | str],
    expected: float | None,
    sel: dict[int, FilletSpec],
    pieces: dict[int, Any],
) -> tuple[float, float, float, dict[int, str], float] | str:
    """The checks of a rebuilt ``shape`` with the fillets ``sel``: (relative volume change,
    relative area change, largest deviation, surface kind per group, the input's volume the
    change is relative to), or the reason it fails
    (a :class:`.search.Failure` naming the fillets of the new faces that failed their own
    check: validity, free edges, deviation; volume and area are the whole solid's).
    ``pieces``: the changed groups' split pieces as they were before the rebuild."""
    diag, tol = job.diag, job.tol
    job.say("validating (analyzer, shell, volume, area, deviation both ways)")
    job.measures.new_round()  # (new faces: the keys of the last attempt's are not needed)
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
    devs: dict[int, float] = {}  # each merged group's deviation (length)
    far: list[Group] = []
    for i, (g, face) in enumerate(merged):
        log_progress(log, "validation: deviation sampled on merged faces", i + 1, len(merged))
        assert g.support is not None
        ms = surfaces[g.support]
        kinds[g.id] = FITTED if isinstance(ms, str) else ms.kind
        n = FITTED_DEVIATION_SAMPLES if isinstance(ms, str) else DEVIATION_SAMPLES
        old = [pieces[k] for k in g.members]
        # (a group rebuilt as in an attempt before: its faces' geometry is the key)
        d = max(
            job.measures.get(
                ("deviation", n, 1e-3 * tol * diag, group_key([face, *old])),
                partial(deviation, old, face, n=n, enough=1e-3 * tol * diag),
            )
        )
        if d > tol * diag:
            far.append(g)
        dev = max(dev, d)
        devs[g.id] = d
    if far:
        return Failure(
            f"surface deviation {dev / diag:.2e} x diagonal (> {tol:g})",
            _fillets_of(split, far, sel),
        )
    # volume and area: on the changed faces when that settles it, else on the whole solid
    changed = [(g, f) for g, f in zip(groups, faces, strict=True) if not g.untouched]
    new = [f for _, f in changed]
    old = [pieces[k] for g, _ in changed for k in g.members]
    origins = component_origins(new, [[pieces[k] for k in g.members] for g, _ in changed])
    owner = list(range(len(changed))) + [i for i, (g, _) in enumerate(changed) for _ in g.members]
    # the fitted groups' faces are measured by OCCT's integrators only when their gaps do
    # not settle the change (on faces of hundreds of knot spans the adaptive integrator
    # took 10 - 16 s a face, and is what the gaps overrule)
    fitted = [i for i, (g, _) in enumerate(changed) if kinds.get(g.id) in (FITTED, ROUNDED)]
    later = np.isin(owner, fitted) if expected is not None else np.zeros(len(owner), bool)
    shares = contributions(new, old, job.vol_ref, VOLUME_TOL, origins, job.measures, later)
    per_group = np.bincount(owner, weights=shares, minlength=len(changed))

    def refused(why: str, dv: float) -> Failure:
        """The volume refusal, blamed on the groups that account for the change (the
        change is the whole attempt's: a fillet tried with accepted ones shares it)."""
        return _blamed(why, per_group, dv, VOLUME_TOL, changed, split, sel)

    dv_local = _gap_settled(
        job, changed, pieces, kinds, devs, shares, owner, per_group, expected, origins,
        integrated=not later.any(),
    )  # fmt: skip
    if dv_local is None and later.any():  # the fitted groups' gaps did not settle it
        shares = contributions(new, old, job.vol_ref, VOLUME_TOL, origins, job.measures)
        per_group = np.bincount(owner, weights=shares, minlength=len(changed))
        dv_local = _gap_settled(
            job, changed, pieces, kinds, devs, shares, owner, per_group, expected, origins
        )
    if dv_local is None:
        dv_local, best = local_volume_shares(
            new, old, job.vol_ref, VOLUME_TOL, expected, shares, origins, job.measures
        )
        # a refusal is blamed by the best measure of each face (the adaptive shares are
        # off on fitted and swept faces, and then account for nothing)
        per_group[:] = np.bincount(owner, weights=best, minlength=len(changed))
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
    # the replaced faces' areas are known to their edges' tolerances only (loose inputs)
    area_tol = AREA_TOL + tolerance_band(old) / job.area0
    da_local = local_area_change(new, old, job.area0, area_tol, job.measures, eps=1e-2 * AREA_TOL)
    if da_local is None:
        da, why = area_change(shape, job.area0, area_tol)
        if why:
            return _area_refused(why, da, area_tol, changed, pieces, job, split, sel)
    else:
        da = da_local
    if job.strict_volume:
        misread = _misread(job, shape, changed, pieces, split, sel)
        if misread is not None:
            return misread
    return dv, da, dev, kinds, base


def _misread(
    job: Job,
    shape: Any,
    changed: list[tuple[Group, Any]],
    pieces: dict[int, Any],
    split: Any,
    sel: dict[int, FilletSpec],
) -> Failure | None:
    """The refusal of a rebuilt ``shape`` that OCCT's default mass properties read as a
    volume change above ``VOLUME_TOL`` from the input (both read whole, each from its own
    point), blamed on the groups whose new faces, read from the new solid's point against
    their pieces, account for it; None when the reading is within it."""
    change = default_volume(shape) / job.vol_ref - 1.0
    if abs(change) <= VOLUME_TOL:
        return None
    o = rough_centre(shape)  # (the reading's own point: its error depends on it)
    shares = (
        np.array(
            [
                default_reading([f], o, job.measures)
                - default_reading([pieces[k] for k in g.members], o, job.measures)
                for g, f in changed
            ]
        )
        / job.vol_ref
    )
    why = (
        f"OCCT's default mass properties (FreeCAD, CadQuery) would read a volume change of "
        f"{change:+.1e} (> {VOLUME_TOL:g})"
    )
    return _blamed(why, shares, change, VOLUME_TOL, changed, split, sel)


def _area_refused(
    why: str,
    da: float,
    tol: float,
    changed: list[tuple[Group, Any]],
    pieces: dict[int, Any],
    job: Job,
    split: Any,
    sel: dict[int, FilletSpec],
) -> Failure:
    """The area refusal, blamed on the groups whose own area change (new face against its
    pieces, relative to the input's area) accounts for ``da``, the measured change beyond
    ``tol``; no fillets blamed when the groups' changes do not account for it."""
    assert job.area0 is not None
    shares = np.array(
        [
            area_delta([f], [pieces[k] for k in g.members], 1e-2 * AREA_TOL, job.measures)
            / job.area0
            for g, f in changed
        ]
    )
    return _blamed(why, shares, da, tol, changed, split, sel)


def _blamed(
    why: str,
    shares: np.ndarray,
    change: float,
    tol: float,
    changed: list[tuple[Group, Any]],
    split: Any,
    sel: dict[int, FilletSpec],
) -> Failure:
    """The refusal ``why`` of a measured ``change`` (relative) naming the fillets of the
    changed groups whose ``shares`` (one per group) account for it (:func:`volume_blame`
    with ``tol``); none when they do not."""
    picked = volume_blame(shares, change, tol)
    fillets = _fillets_of(split, [changed[i][0] for i in picked], sel)
    if fillets:
        names = ", ".join(map(str, sorted(fillets)[:5])) + (", ..." if len(fillets) > 5 else "")
        why += f"; {float(shares[picked].sum()):.1e} of it on the faces of fillets {names}"
    return Failure(why, fillets)


def _gap_settled(
    job: Job,
    changed: list[tuple[Group, Any]],
    pieces: dict[int, Any],
    kinds: dict[int, str],
    devs: dict[int, float],
    shares: np.ndarray,
    owner: list[int],
    per_group: np.ndarray,
    expected: float | None,
    origins: np.ndarray,
    integrated: bool = True,
) -> float | None:
    """The relative volume change measured from the gap between each new face and the
    pieces it replaces (:func:`.gap_measure.gap_volume`), when OCCT's integrators and the
    fits' own measure ``expected`` disagree on the fitted groups, or when the fitted
    groups were not integrated (``integrated`` False: their ``shares`` are 0): taken when
    the fitted groups' gap agrees with ``expected``, and the other merged groups' gap with
    the integrators' or their change is bounded within the budget by their deviations
    (``devs``, per group, times their areas; ``shares``: the faces' contributions,
    ``owner``: each face's group, ``origins``: each face's point; faces on their own
    surface count 0: their change of outline is the neighbours' gap).
    The gap values go into ``per_group`` (the refusal's blame). None otherwise: the
    integrators decide, as before."""
    fitted = [i for i, (g, _) in enumerate(changed) if kinds.get(g.id) in (FITTED, ROUNDED)]
    if expected is None or not fitted:
        return None
    budget = 0.1 * VOLUME_TOL
    if integrated and abs(float(per_group[fitted].sum()) - expected) <= budget:
        return None
    gaps = np.zeros(len(changed))
    areas = np.zeros(len(changed))
    rest = [i for i in range(len(changed)) if i not in set(fitted)]
    merged = [i for i in rest if changed[i][0].support is not None]
    for part in (fitted, merged):  # the fitted groups first: most attempts end there
        for i in part:
            g, face = changed[i]
            old = [pieces[k] for k in g.members]
            # (a group rebuilt as in an attempt before: its faces' geometry is the key)
            measured = job.measures.get(
                ("gap", group_key([face, *old])), partial(gap_volume, face, old)
            )
            if measured is None:
                return None
            gaps[i], areas[i] = measured[0] / job.vol_ref, measured[1]
        if part is fitted and not _fits_agree(float(gaps[fitted].sum()), expected, budget):
            return None
    # the exact groups' change bounded by their deviations: sum of d x area
    bound = sum(devs.get(changed[i][0].id, np.inf) * areas[i] for i in merged) / job.vol_ref
    agree = abs(float(gaps[rest].sum() - per_group[rest].sum())) <= budget
    if not agree and bound > budget:
        # the adaptive integrator is off on some exact faces too (swept ones as built):
        # their change settled face by face (:func:`.local_measure.local_volume_shares`)
        mask = np.isin(np.asarray(owner), rest)
        new = [changed[i][1] for i in rest]
        old = [pieces[k] for i in rest for k in changed[i][0].members]
        settled, _ = local_volume_shares(
            new, old, job.vol_ref, VOLUME_TOL, None, shares[mask], origins[mask], job.measures
        )
        if settled is None or abs(float(gaps[rest].sum()) - settled) > budget:
            return None
    read = float(per_group[fitted].sum())
    job.say(
        f"volume measured from the gaps of the new faces: {gaps.sum():.1e} (the fits "
        f"{expected:.1e}" + (f", OCCT's integrator {read:.1e} on them)" if integrated else ")")
    )
    per_group[:] = gaps
    return float(gaps.sum())


def _fits_agree(gap: float, expected: float, budget: float) -> bool:
    """Whether the fitted groups' gap ``gap`` and the fits' own measure ``expected`` (both
    relative volume changes) settle their change: within ``budget`` of each other, or both
    so small that the change is within half the tolerance whichever is right (the gap
    1.4e-7, the fits 1.2e-8, OCCT's integrators -3.5e-6 on a 229-face bracket)."""
    disagree = abs(gap - expected)
    return disagree <= budget or max(abs(gap), abs(expected)) + disagree <= 0.5 * VOLUME_TOL


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
