"""The merged surface of every supporting face (exact where the geometry allows, fitted
otherwise), the fitted faces' passes on the full split (a failing face keeps the blends
its misfit is traced to, or its fillets), the cylinder field's second pass and the
fillets merged whole into one face."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy
from OCP.GeomAbs import GeomAbs_Cylinder, GeomAbs_Plane
from OCP.TopoDS import TopoDS

from medax.cad.simplify.chains import Chain, chain_arcs
from medax.cad.simplify.cylinder_field import cylinder_surface
from medax.cad.simplify.fitted import (
    FittedSurface,
    Refusal,
    graph_setup,
    graph_surface,
)
from medax.cad.simplify.groups import Group, GroupError, build_groups
from medax.cad.simplify.job import (
    ACCEPT_SHARE,
    FIT_SHARE,
    FITTED,
    Job,
)
from medax.cad.simplify.medial import AXIS, TRACED
from medax.cad.simplify.occ import edges_of
from medax.cad.simplify.ring import NOT_A_RING, ring_surface
from medax.cad.simplify.rounded import rounded_surface
from medax.cad.simplify.search import halves_of, riders
from medax.cad.simplify.specs import BlendInput, CornerSpec, FilletSpec
from medax.cad.simplify.split import split_along
from medax.cad.simplify.surfaces import Half, MergedSurface, merged_surface
from medax.errors import CadError


def cascade(  # type: ignore[no-untyped-def]
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


def refresh_surfaces(job: Job) -> None:
    """Merged surface per supporting face into ``job.surfaces``: an exact one, or
    ``FITTED`` for a plane whose pieces have none (fitted per attempt); fillets of other
    faces move to ``job.kept``. Exact surfaces depend on which halves a face gets, so this
    runs again whenever fillets are dropped."""
    specs, kept = job.specs, job.kept
    while True:
        cascade(specs, job.corners, kept, job.chains)
        surfaces, failed = surfaces_for(job, specs, job.corners)
        if not failed:
            job.surfaces = surfaces
            return
        for f, (sup, why) in failed.items():
            if f not in kept:
                kept[f] = why
                job.no_surface[f] = sup
            specs.pop(f, None)


def surfaces_for(
    job: Job, specs: dict[int, FilletSpec], corners: dict[int, CornerSpec]
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
        # a fillet merged whole (see :func:`one_sided`) has the same (fillet, edge) as its
        # half: the medial parameter tells them apart
        key = (sup, sup in with_corner, *sorted((f, e, job.medials[f].mid) for f, e in hs))
        if key not in job.exact:
            job.exact[key] = surface_of(job, sup, hs, sup in with_corner)
        ms = job.exact[key]
        if isinstance(ms, str) and ms != FITTED:
            return surfaces, {f: (sup, f"supporting face {sup}: {ms}") for f, _ in hs}
        surfaces[sup] = ms
    return surfaces, {}


def _exact_surface(
    job: Job, support: Any, sup: int, hs: list[tuple[int, int]]
) -> MergedSurface | str:
    """The exact merged surface of ``support`` (face ``sup``) with the halves ``hs``, or
    why there is none (a chain member with no iso-line section, a profile no exact route
    takes, an OCCT construction failure)."""
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
        return merged_surface(support, halves, job.btol)
    except (ValueError, RuntimeError) as err:  # OCCT construction failures
        return f"surface construction failed: {err}"


def surface_of(
    job: Job, sup: int, hs: list[tuple[int, int]], with_corner: bool
) -> MergedSurface | str:
    """The merged surface of supporting face ``sup`` with the halves ``hs`` ((fillet, smooth
    edge) pairs): exact, ``FITTED``, or the reason there is none."""
    support = job.face(sup)
    planar = BRepAdaptor_Surface(support).GetType() == GeomAbs_Plane
    if with_corner:
        return FITTED if planar else "corner or bridged pieces on a curved face"
    ms = _exact_surface(job, support, sup, hs)
    if isinstance(ms, str) and (planar or ring_kind(support) or graph_kind(support)):
        return FITTED
    if isinstance(ms, str):
        kind = str(BRepAdaptor_Surface(support).GetType()).split("_")[-1].lower()
        return (
            f"{ms}; the fitted routes take planar and cylindrical supporting faces "
            f"only (this one is a {kind})"
        )
    return ms


def one_sided(job: Job, blends: BlendInput) -> None:
    """Fillets kept because one supporting face has no surface for their half are merged
    whole into the other supporting face, where that face then has an exact surface (an
    extrusion or revolution whose profile runs across the whole fillet): the face that had
    none is left as it was (or fitted without this fillet, when the fillet's own piece held
    its misfit: a fillet ending at a step, where a rib ends on a plate), the fillet still
    goes and the shape is the same. Not for
    fillets meeting corner blends, riding on or ridden by fillets, or traced ones."""
    by_face = {s.face: s for s in blends.fillets}
    linked = blends.linked
    for f, why in sorted(job.kept.items()):
        bad = job.no_surface.get(f)
        spec, m = by_face.get(f), job.medials.get(f)
        if bad is None or spec is None or m is None or f in linked or m.iso in (TRACED, AXIS):
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
        surfaces, failed = surfaces_for(job, trial, job.corners)
        if failed or not isinstance(surfaces.get(spec.supporting[k]), MergedSurface):
            job.medials[f] = m
            continue
        job.specs, job.surfaces = trial, surfaces
        job.whole[f] = spec.supporting[k]
        job.kept.pop(f)
        job.say(f"fillet {f} merged whole into face {spec.supporting[k]} ({why[:60]}...)")


def fitted_surface(job: Job, split: Any, g: Group, probe: bool = False) -> FittedSurface | str:
    """The fitted surface of group ``g`` (cached by its support and its members' origins);
    with ``probe`` the cheap height-field check only (see :func:`graph_surface`)."""
    assert g.support is not None
    origins = sorted(split.origin[k] for k in g.members)
    key = (int(probe), g.support, *origins)
    if job.cylinder_field and ring_kind(job.face(g.support)):
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
            # a rounded box's face (cylinder strips, sphere corners) has an exact surface
            # (made once for the probe and the full fit: key -2)
            exact = ring
            if isinstance(ring, str) and _tight(members, fit_tol):
                rkey = (-2, g.support, *origins)
                if rkey not in job.cache:
                    job.cache[rkey] = rounded_surface(support, members, job.btol)
                exact = job.cache[rkey]
            if isinstance(exact, FittedSurface):
                job.cache[key] = exact
            elif isinstance(ring, str) and not ring_kind(support):
                # (the probe's setup and fit serve the full fit of the same group)
                skey = key[1:]
                if skey not in job.setups:
                    job.setups[skey] = graph_setup(support, members, job.btol)
                setup = job.setups[skey]
                flat = graph_surface(support, members, fit_tol, job.btol, probe, setup, accept)
                if isinstance(flat, str) and ring_applies(ring):
                    flat = Refusal(f"{flat}; ring route: {ring}", culprits_of(flat))
                job.cache[key] = flat
            elif isinstance(ring, str) and job.cylinder_field:
                # a cylinder the ring route refused: the field over the cylinder
                cyl = cylinder_surface(support, members, fit_tol, job.btol, probe, accept)
                if isinstance(cyl, str) and ring_applies(ring):
                    cyl = f"{cyl}; ring route: {ring}"
                job.cache[key] = cyl
            else:
                job.cache[key] = ring
        except Exception as err:  # OCCT failures while sampling the pieces
            job.cache[key] = f"fitting failed ({type(err).__name__}: {err})"
    return job.cache[key]


def _tight(members: list[Any], tol: float) -> bool:
    """Whether every edge of ``members`` lies on its faces within ``tol`` (its own
    tolerance): the rounded-box route's closed form is taken on such pieces only. On a
    loose input (edges 2 - 4e-3 off, isolated_blends_test_28) its faces met the loose
    boundaries with volume checks failing where the fitted routes' whole merges pass
    (17 against 45 of 52 fillets removed)."""
    return all(BRep_Tool.Tolerance_s(TopoDS.Edge(e)) <= tol for f in members for e in edges_of(f))


def ring_kind(face: Any) -> bool:
    """Whether a supporting face takes the ring route and then the field over its
    cylinder, not the height field over a plane (a cylinder: see :mod:`.ring`,
    :mod:`.cylinder_field`)."""
    return BRepAdaptor_Surface(face).GetType() == GeomAbs_Cylinder


def graph_kind(face: Any) -> bool:
    """Whether a curved supporting face may take the height-field route (over its mean
    plane): any surface but a cylinder (ring route) that converts to a B-spline; the fit
    itself refuses a merged face that is no graph."""
    return BRepAdaptor_Surface(face).GetType() not in (GeomAbs_Plane, GeomAbs_Cylinder)


def ring_applies(why: str) -> bool:
    """Whether the ring route's refusal ``why`` came after the group looked like a ring (a
    fit that missed, a pole on the face; not a group of another shape): worth naming next
    to the planar route's reason."""
    return not why.startswith(NOT_A_RING)


def split_job(
    job: Job, sel: dict[int, FilletSpec], csel: dict[int, CornerSpec], keep: bool = False
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
        # on a fresh copy of the topology (the geometry shared): the healing in a rebuild
        # (``ShapeFix_Shape``) changes the edges it keeps in place, which would otherwise
        # change the working solid's own faces (seen: its volume 17582 -> -11797 after one
        # rebuild of a loose input, so the next measures and attempts started from a broken
        # solid; the split's own pieces are still changed so)
        split = split_along(BRepBuilderAPI_Copy(job.work, False, False).Shape(), tools)
    if keep:
        job.last_split = (tools, split)
    groups = build_groups(
        split,
        {f: s.supporting for f, s in sel.items()},
        {c: cs.supporting for c, cs in csel.items()},
    )
    return split, groups


def fit_pass(job: Job) -> None:
    """Check every fitted face on the full split, first cheaply (is it a height field at
    all?) until no face fails, then with the full fit; fillets of faces that fail are kept
    (with the reason) before the rebuild is tried, so bisection is not spent on them; so are
    fillets that a group on the full split cannot be formed with (:class:`GroupError`).
    Where a face's misfit is traced to some of its blends, only those are kept and the face
    is fitted again (each round keeps at least one blend, so the rounds end)."""
    for probe in (True, False):
        for _ in range(len(job.specs) + len(job.corners) + 1):
            if not fit_round(job, probe):
                break
            refresh_surfaces(job)


def fit_round(job: Job, probe: bool) -> bool:
    """One round of :func:`fit_pass`; True when some face failed (and was dropped)."""
    fitted = {s for s, v in job.surfaces.items() if v == FITTED}
    if not fitted or not job.specs:
        return False
    try:
        split, groups = split_job(job, job.specs, job.corners, keep=True)
    except GroupError as err:  # traced to fillets: keep them now, not after a search
        blamed = {f for c in err.faces if c in job.corners for f in job.corners[c].fillets}
        blamed |= err.faces & set(job.specs)
        if not blamed:
            return False
        job.say(f"fillets {sorted(blamed)} kept: {err}")
        for f in blamed:
            job.specs.pop(f, None)
            job.kept.setdefault(f, f"rebuild failed: {err}")
        cascade(job.specs, job.corners, job.kept, job.chains)
        return True
    except CadError:
        return False  # the attempt will report it
    bad: dict[int, str] = {}
    traced: dict[int, set[int]] = {}  # support -> the blends its misfit is traced to
    for g in groups:
        if g.support is not None and g.support in fitted:
            r = fitted_surface(job, split, g, probe)
            if isinstance(r, str):
                bad[g.support] = r
                traced[g.support] = {
                    split.origin[g.members[i]] for i in culprits_of(r) if i < len(g.members)
                } & (set(job.specs) | set(job.corners))
    if not bad:
        return False
    job.say(f"fitted surfaces failed on faces {sorted(bad)}")
    for sup, why in bad.items():
        culprits = traced[sup]
        if culprits:  # the misfit lies on these blends' pieces: the others are tried again
            keep_culprits(job, sup, why, culprits)
            continue
        # else the second pass's newcomers first (:func:`cylinder_pass`), or a chain of
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
    cascade(job.specs, job.corners, job.kept, job.chains)
    return True


def culprits_of(why: str) -> frozenset[int]:
    """The members a fitted route's refusal is traced to (none for a plain reason)."""
    return why.culprits if isinstance(why, Refusal) else frozenset()


def keep_culprits(job: Job, sup: int, why: str, culprits: set[int]) -> None:
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


def cylinder_pass(job: Job, tried: dict[int, FilletSpec], corners: dict[int, CornerSpec]) -> bool:
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
        and ring_kind(job.face(sup))
    }  # fmt: skip
    if not cands:
        return False
    job.say(f"{len(cands)} fillets kept at cylinders tried with the cylinder field")
    old = {f: (job.kept.pop(f), job.no_surface.pop(f)) for f in cands}
    job.specs.update({f: tried[f] for f in cands})
    job.prefer = set(cands)
    refresh_surfaces(job)
    fit_pass(job)
    job.prefer = set()
    for f in cands:
        if f not in job.specs and f not in job.kept:  # (dropped without a reason of its own)
            job.kept[f], job.no_surface[f] = old[f]
    return True
