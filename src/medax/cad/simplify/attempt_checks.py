"""The checks of a rebuilt solid (simplify's validation of one attempt): validity, closed
shells, deviation both ways, and the volume and area changes on the changed faces, by
OCCT's integrators or, on fitted groups, by the gaps between each new face and the pieces
it replaces; each refusal blamed on the fillets whose faces account for it."""

from __future__ import annotations

import logging
from functools import partial
from typing import Any

import numpy as np
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.TopAbs import TopAbs_SHELL

from medax._progress import log_progress
from medax.cad.simplify.gap_measure import gap_volume
from medax.cad.simplify.groups import Group
from medax.cad.simplify.job import (
    AREA_TOL,
    FITTED,
    FITTED_DEVIATION_SAMPLES,
    VOLUME_TOL,
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
from medax.cad.simplify.occ import count
from medax.cad.simplify.result import DEVIATION_SAMPLES
from medax.cad.simplify.rounded import ROUNDED
from medax.cad.simplify.search import Failure, volume_blame
from medax.cad.simplify.specs import FilletSpec
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

log = logging.getLogger(__name__)


def fillets_of(split: Any, groups: list[Group], sel: dict[int, FilletSpec]) -> set[int]:
    """The fillets of ``sel`` with a half (or the whole) in one of ``groups``."""
    return {split.origin[k] for g in groups for k in g.halves} & set(sel)


def validated(
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
        return Failure("rebuilt solid not valid (BRepCheck_Analyzer)", fillets_of(split, bad, sel))
    shells = count(job.work, TopAbs_SHELL)  # an outer shell and one per cavity
    if c.shells != shells or not c.closed:
        open_faces = free_edge_faces(shape)
        bad = [g for g, f in merged if any(f.IsSame(o) for o in open_faces)]
        return Failure(
            f"rebuilt solid has {c.shells} shells (the input {shells}) / free edges",
            fillets_of(split, bad, sel),
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
            fillets_of(split, far, sel),
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
    fillets = fillets_of(split, [changed[i][0] for i in picked], sel)
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
        if part is fitted and not fits_agree(float(gaps[fitted].sum()), expected, budget):
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


def fits_agree(gap: float, expected: float, budget: float) -> bool:
    """Whether the fitted groups' gap ``gap`` and the fits' own measure ``expected`` (both
    relative volume changes) settle their change: within ``budget`` of each other, or both
    so small that the change is within half the tolerance whichever is right (the gap
    1.4e-7, the fits 1.2e-8, OCCT's integrators -3.5e-6 on a 229-face bracket)."""
    disagree = abs(gap - expected)
    return disagree <= budget or max(abs(gap), abs(expected)) + disagree <= 0.5 * VOLUME_TOL
