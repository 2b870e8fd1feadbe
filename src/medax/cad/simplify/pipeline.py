"""Fillet simplification of a solid (the paper's section 3, steps 3 to 5).

:func:`simplify` splits every fillet it can handle along its medial curve, merges each half
into its supporting face on one exact surface, rebuilds the solid on shared edges and
validates it against the original. Fillets it cannot handle are kept, each with its reason;
when the rebuilt solid fails validation the failing fillets are found by bisection over
independent clusters and kept. The input solid is never modified and an invalid solid is
never returned: at worst the result is the input itself with every fillet kept.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy
from OCP.GeomAbs import GeomAbs_Plane
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopoDS import TopoDS

from medax.cad.simplify.corner import corner_arcs, plane_normal
from medax.cad.simplify.fitted import FittedSurface, graph_surface
from medax.cad.simplify.groups import Group, build_groups
from medax.cad.simplify.medial import Medial, medial_curve
from medax.cad.simplify.occ import count, diagonal, shape_map, small_list
from medax.cad.simplify.rebuild import build_solid
from medax.cad.simplify.specs import BlendInput, CornerSpec, FilletSpec
from medax.cad.simplify.split import split_along
from medax.cad.simplify.surfaces import Half, MergedSurface, merged_surface
from medax.cad.simplify.validate import check, deviation, volume, volume_change
from medax.errors import CadError

log = logging.getLogger(__name__)

#: Default deviation tolerance, relative to the part's diagonal (the issue's ``1e-5 x``).
DEVIATION_TOL = 1e-5
#: Largest accepted relative volume change.
VOLUME_TOL = 1e-6
#: The deviation check samples an n x n UV grid on every old and new face (kept inside).
DEVIATION_SAMPLES = 8
#: Geometric tolerance of the construction, relative to the diagonal.
BUILD_TOL = 1e-7
#: A fitted surface must be within this share of the deviation tolerance (measured).
FIT_SHARE = 0.1
#: Deviation samples per face (n x n) for groups on a fitted surface.
FITTED_DEVIATION_SAMPLES = 16
#: Marker in the surface table: this supporting plane gets a fitted surface per attempt.
FITTED = "fitted"


@dataclass(frozen=True)
class FaceGroup:
    """A face of the result and what it came from: original faces used ``whole`` and the
    fillet faces of which one ``half`` was absorbed; ``surface`` is ``extrusion``,
    ``revolution`` (new exact surfaces) or ``original``."""

    new_face: int
    whole: tuple[int, ...]
    halves: tuple[int, ...]
    surface: str


@dataclass
class SimplifyResult:
    """Outcome of :func:`simplify` (see :meth:`report` for the JSON form)."""

    shape: Any
    faces_before: int
    faces_after: int
    blends_removed: list[int]
    blends_kept: list[tuple[int, str]]
    valid: bool
    volume_before: float
    volume_after: float
    max_deviation: float
    diagonal: float
    face_groups: list[FaceGroup]
    time_s: float
    medial_error: float = 0.0
    fit_error: float = 0.0
    notes: list[str] = field(default_factory=list)

    @property
    def volume_rel_change(self) -> float:
        """(after - before) / before."""
        return (self.volume_after - self.volume_before) / self.volume_before

    def report(self) -> dict[str, Any]:
        """The JSON-ready report (keys of the issue)."""
        return {
            "faces_before": self.faces_before,
            "faces_after": self.faces_after,
            "blends_removed": sorted(self.blends_removed),
            "blends_kept": [{"face": f, "reason": r} for f, r in sorted(self.blends_kept)],
            "valid": self.valid,
            "volume_before": self.volume_before,
            "volume_after": self.volume_after,
            "volume_rel_change": self.volume_rel_change,
            "max_deviation": {
                "absolute": self.max_deviation,
                "relative_to_diagonal": self.max_deviation / self.diagonal,
            },
            "diagonal": self.diagonal,
            "medial_equidistance_error": self.medial_error,
            "max_fit_error": {
                "absolute": self.fit_error,
                "relative_to_diagonal": self.fit_error / self.diagonal,
            },
            "deviation_samples_per_face": DEVIATION_SAMPLES**2,
            "face_groups": [
                {
                    "new_face": g.new_face,
                    "original_faces": list(g.whole),
                    "fillet_halves": list(g.halves),
                    "surface": g.surface,
                }
                for g in self.face_groups
            ],
            "notes": self.notes,
            "time_s": self.time_s,
        }


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


def simplify(
    shape: Any,
    blends: BlendInput,
    tol: float = DEVIATION_TOL,
    progress: Callable[[str], None] | None = None,
) -> SimplifyResult:
    """Simplify the fillets of ``shape`` described by ``blends``.

    ``tol``: deviation tolerance relative to the diagonal. ``progress`` receives one-line
    messages (the CLI prints them on stderr).
    """
    t0 = time.perf_counter()
    say = progress or (lambda msg: log.info(msg))
    work = BRepBuilderAPI_Copy(shape, True, False).Shape()
    diag = diagonal(work)
    btol = BUILD_TOL * diag
    fmap = shape_map(work, TopAbs_FACE)
    emap = shape_map(work, TopAbs_EDGE)
    nfaces = fmap.Size()
    vol0 = volume(work)
    kept: dict[int, str] = dict(blends.refused)
    medials: dict[int, Medial] = {}
    for spec in blends.fillets:
        m = medial_curve(
            TopoDS.Face(fmap.FindKey(spec.face + 1)),
            *[TopoDS.Edge(emap.FindKey(i + 1)) for i in spec.smooth_edges],
        )
        if isinstance(m, str):
            kept[spec.face] = m
        else:
            medials[spec.face] = m
    corners, arcs = _corners(blends, medials, fmap, kept)
    _keep_next_to_corners(work, blends, medials, kept)
    say(f"{len(medials)} fillets with a medial curve, {len(corners)} corner blends split")
    specs = {s.face: s for s in blends.fillets if s.face in medials}
    _cascade(specs, corners, kept)
    surfaces = _surfaces(specs, medials, fmap, emap, kept, btol, corners)
    n_fit = sum(1 for v in surfaces.values() if isinstance(v, str))
    say(f"{len(specs)} fillets on {len(surfaces)} merged faces ({n_fit} fitted)")
    cache: dict[tuple[int, ...], FittedSurface | str] = {}

    def attempt(sel: dict[int, FilletSpec]) -> _Attempt | str:
        csel = {c: cs for c, cs in corners.items() if set(cs.fillets) <= set(sel)}
        return _attempt(work, sel, csel, arcs, medials, surfaces, fmap, diag, vol0, tol, say, cache)

    if n_fit:
        _fit_pass(work, specs, corners, arcs, medials, surfaces, fmap, kept, diag, tol, say, cache)
    result = attempt(specs) if specs else None
    if isinstance(result, str):
        say(f"rebuild with all fillets failed ({result}); bisecting")
        good = _bisect(specs, attempt, kept, say)
        result = attempt(good) if good else None
        if isinstance(result, str):
            for f in good:
                kept[f] = f"rebuild failed: {result}"
            result = None
        specs = good
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
        vol1 = vol0
        valid = check(work).valid
    else:
        final, dev, vol1, valid = result.shape, result.deviation, result.volume, True
        groups_out = _face_groups(result)
    notes = [] if removed else ["no fillet simplified: output equals input"]
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
        medial_error=max((medials[f].error for f in removed if f in medials), default=0.0),
        fit_error=result.fit_error if result is not None else 0.0,
        notes=notes,
    )


def _keep_next_to_corners(shape, blends, medials, kept) -> None:  # type: ignore[no-untyped-def]
    """Fillets sharing an edge with a blend that stays (a refused or unsplit corner blend)
    are kept too: their medial curves would have to end at that blend's centre."""
    from medax.cad.simplify.specs import edge_face_map

    refused = {f for f, _ in blends.refused} | {c.face for c in blends.corners if c.face in kept}
    if not refused:
        return
    fmap = shape_map(shape, TopAbs_FACE)
    e2f = edge_face_map(shape)
    from medax.cad.simplify.occ import edges_of

    for spec in blends.fillets:
        if spec.face not in medials:
            continue
        face = fmap.FindKey(spec.face + 1)
        near = {
            fmap.FindIndex(g) - 1 for e in edges_of(face) for g in small_list(e2f.FindFromKey(e))
        } & refused
        if near:
            medials.pop(spec.face)
            kept[spec.face] = f"meets blend {min(near)}, which is kept"


def _corners(blends, medials, fmap, kept) -> tuple[dict[int, CornerSpec], dict[int, list[Any]]]:  # type: ignore[no-untyped-def]
    """Corner blends that can be split (a sphere between planes, every fillet meeting it
    with a medial curve) and their split arcs; the others go to ``kept``."""
    by_face = {s.face: s for s in blends.fillets}
    corners: dict[int, CornerSpec] = {}
    arcs: dict[int, list[Any]] = {}
    for cs in blends.corners:
        missing = [f for f in cs.fillets if f not in medials]
        if missing:
            kept[cs.face] = f"corner blend: fillets {missing} meeting it are kept"
            continue
        normals = {}
        for sup in cs.supporting:
            n = plane_normal(TopoDS.Face(fmap.FindKey(sup + 1)))
            if n is None:
                break
            normals[sup] = n
        if len(normals) != len(cs.supporting):
            kept[cs.face] = "corner blend between faces that are not planes (not supported)"
            continue
        pairs = [by_face[f].supporting for f in cs.fillets]
        r = corner_arcs(TopoDS.Face(fmap.FindKey(cs.face + 1)), pairs, normals)
        if isinstance(r, str):
            kept[cs.face] = r
            continue
        corners[cs.face], arcs[cs.face] = cs, r[0]
    return corners, arcs


def _cascade(specs: dict[int, FilletSpec], corners: dict[int, CornerSpec], kept) -> None:  # type: ignore[no-untyped-def]
    """A corner blend goes only with all its fillets, and a fillet only with its corners:
    drop both ways until nothing changes."""
    changed = True
    while changed:
        changed = False
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


def _halves_of(specs: dict[int, FilletSpec]) -> dict[int, list[tuple[int, int]]]:
    """supporting face -> [(fillet face, smooth edge index)]."""
    out: dict[int, list[tuple[int, int]]] = {}
    for s in specs.values():
        for e, sup in zip(s.smooth_edges, s.supporting, strict=True):
            out.setdefault(sup, []).append((s.face, e))
    return out


def _surfaces(specs, medials, fmap, emap, kept, btol, corners) -> dict[int, MergedSurface | str]:  # type: ignore[no-untyped-def]
    """Merged surface per supporting face: an exact one, or ``FITTED`` for a plane whose
    pieces have none (fitted per attempt); fillets of other faces move to ``kept``."""
    while True:
        _cascade(specs, corners, kept)
        with_corner = {s for cs in corners.values() for s in cs.supporting}
        surfaces: dict[int, MergedSurface | str] = {}
        failed = False
        for sup, hs in _halves_of(specs).items():
            support = TopoDS.Face(fmap.FindKey(sup + 1))
            planar = BRepAdaptor_Surface(support).GetType() == GeomAbs_Plane
            if sup in with_corner:
                ms: MergedSurface | str = FITTED if planar else "corner pieces on a curved face"
            else:
                halves = [
                    Half(
                        TopoDS.Face(fmap.FindKey(f + 1)),
                        medials[f],
                        TopoDS.Edge(emap.FindKey(e + 1)),
                    )
                    for f, e in hs
                ]
                try:
                    ms = merged_surface(support, halves, btol)
                except (ValueError, RuntimeError) as err:  # OCCT construction failures
                    ms = f"surface construction failed: {err}"
                if isinstance(ms, str) and planar:
                    ms = FITTED
            if isinstance(ms, str) and ms != FITTED:
                for f, _ in hs:
                    kept.setdefault(f, f"supporting face {sup}: {ms}")
                    specs.pop(f, None)
                failed = True
                break
            surfaces[sup] = ms
        if not failed:
            return surfaces


def _fitted(split, g: Group, fmap, cache, diag: float, tol: float, probe: bool = False):  # type: ignore[no-untyped-def]
    """The fitted surface of group ``g`` (cached by its support and its members' origins);
    with ``probe`` the cheap height-field check only (see :func:`graph_surface`)."""
    assert g.support is not None
    key = (int(probe), g.support, *sorted(split.origin[k] for k in g.members))
    if key not in cache:
        members = [TopoDS.Face(split.face_map.FindKey(k + 1)) for k in g.members]
        plane = TopoDS.Face(fmap.FindKey(g.support + 1))
        try:
            cache[key] = graph_surface(
                plane, members, FIT_SHARE * tol * diag, BUILD_TOL * diag, probe=probe
            )
        except Exception as err:  # OCCT failures while sampling the pieces
            cache[key] = f"fitting failed ({type(err).__name__}: {err})"
    return cache[key]


def _fit_pass(
    work, specs, corners, arcs, medials, surfaces, fmap, kept, diag, tol, say, cache
) -> None:  # type: ignore[no-untyped-def]
    """Check every fitted face on the full split, first cheaply (is it a height field at
    all?) until no face fails, then with the full fit; fillets of faces that fail are kept
    (with the reason) before the rebuild is tried, so bisection is not spent on them."""
    for probe in (True, False):
        for _ in range(len(surfaces) + 1):
            if not _fit_round(
                work,
                specs,
                corners,
                arcs,
                medials,
                surfaces,
                fmap,
                kept,
                diag,
                tol,
                say,
                cache,
                probe,
            ):
                break


def _fit_round(
    work, specs, corners, arcs, medials, surfaces, fmap, kept, diag, tol, say, cache, probe
) -> bool:  # type: ignore[no-untyped-def]
    """One round of :func:`_fit_pass`; True when some face failed (and was dropped)."""
    fitted = [s for s, v in surfaces.items() if v == FITTED]
    if not fitted or not specs:
        return False
    tools = [medials[f].edge for f in specs] + [e for c in corners for e in arcs[c]]
    try:
        split = split_along(work, tools)
        groups = build_groups(
            split,
            {f: s.supporting for f, s in specs.items()},
            {c: cs.supporting for c, cs in corners.items()},
        )
    except CadError:
        return False  # the attempt will report it
    bad: dict[int, str] = {}
    for g in groups:
        if g.support is not None and g.support in fitted:
            r = _fitted(split, g, fmap, cache, diag, tol, probe)
            if isinstance(r, str):
                bad[g.support] = r
    if not bad:
        return False
    say(f"fitted surfaces failed on faces {sorted(bad)}: their fillets are kept")
    for sup, why in bad.items():
        surfaces.pop(sup, None)
        for f, s in list(specs.items()):
            if sup in s.supporting:
                specs.pop(f)
                kept.setdefault(f, f"supporting face {sup}: {why}")
    _cascade(specs, corners, kept)
    live = {x for s in specs.values() for x in s.supporting}
    for sup in list(surfaces):
        if sup not in live:
            surfaces.pop(sup)
    return True


def _attempt(
    work, sel, csel, arcs, medials, surfaces, fmap, diag, vol0, tol, say, cache
) -> _Attempt | str:  # type: ignore[no-untyped-def]
    fit_err = 0.0
    try:
        say(f"splitting {len(sel)} fillets and {len(csel)} corner blends along medial curves")
        tools = [medials[f].edge for f in sel] + [e for c in csel for e in arcs[c]]
        split = split_along(work, tools)
        groups = build_groups(
            split,
            {f: s.supporting for f, s in sel.items()},
            {c: cs.supporting for c, cs in csel.items()},
        )
        used: dict[int, Any] = {}
        for g in groups:
            if g.support is None:
                continue
            ms = surfaces[g.support]
            if ms == FITTED:
                fs = _fitted(split, g, fmap, cache, diag, tol)
                if isinstance(fs, str):
                    return f"face {g.support}: {fs}"
                used[g.support] = fs.surface
                fit_err = max(fit_err, fs.error)
            else:
                used[g.support] = ms.surface
        say(f"rebuilding: {len(groups)} faces")
        shape, faces = build_solid(split, groups, used, BUILD_TOL * diag)
    except CadError as err:
        return str(err)
    except Exception as err:  # OCCT Standard_Failure subclasses, translated here
        return f"OCCT failed while rebuilding ({type(err).__name__}: {err})"
    say("validating (analyzer, shell, volume, deviation both ways)")
    c = check(shape)
    if not c.valid:
        return "rebuilt solid not valid (BRepCheck_Analyzer)"
    if c.shells != 1 or not c.closed:
        return f"rebuilt solid has {c.shells} shells / free edges"
    dv, why = volume_change(shape, vol0, VOLUME_TOL)
    if why:
        return why
    dev = 0.0
    kinds: dict[int, str] = {}
    for g, face in zip(groups, faces, strict=True):
        if g.support is None:
            continue
        ms = surfaces[g.support]
        kinds[g.id] = FITTED if ms == FITTED else ms.kind
        n = FITTED_DEVIATION_SAMPLES if ms == FITTED else DEVIATION_SAMPLES
        old = [TopoDS.Face(split.face_map.FindKey(k + 1)) for k in g.members]
        dev = max(dev, *deviation(old, face, n=n, enough=1e-3 * tol * diag))
    if dev > tol * diag:
        return f"surface deviation {dev / diag:.2e} x diagonal (> {tol:g})"
    halves_origin = {g.id: [split.origin[k] for k in g.halves] for g in groups}
    return _Attempt(
        shape, groups, faces, dev, vol0 * (1 + dv), split.origin, halves_origin, kinds, fit_err
    )


def _clusters(specs: dict[int, FilletSpec]) -> list[list[int]]:
    """Fillets linked through shared supporting faces (they must be merged together)."""
    by_sup = _halves_of(specs)
    seen: set[int] = set()
    out = []
    for f in specs:
        if f in seen:
            continue
        stack, comp = [f], []
        while stack:
            x = stack.pop()
            if x in seen:
                continue
            seen.add(x)
            comp.append(x)
            for sup in specs[x].supporting:
                stack.extend(y for y, _ in by_sup[sup])
        out.append(comp)
    return out


def _bisect(specs, attempt, kept, say) -> dict[int, FilletSpec]:  # type: ignore[no-untyped-def]
    clusters = _clusters(specs)
    good: dict[int, FilletSpec] = {}

    def rec(cs: list[list[int]]) -> None:
        sel = {f: specs[f] for c in cs for f in c}
        r = attempt(sel)
        if not isinstance(r, str):
            good.update(sel)
        elif len(cs) == 1:
            for f in cs[0]:
                kept[f] = f"rebuild failed: {r}"
            say(f"fillets {cs[0]} kept: {r}")
        else:
            rec(cs[: len(cs) // 2])
            rec(cs[len(cs) // 2 :])

    if len(clusters) > 1:
        rec(clusters[: len(clusters) // 2])
        rec(clusters[len(clusters) // 2 :])
    else:
        rec(clusters)
    return good


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
