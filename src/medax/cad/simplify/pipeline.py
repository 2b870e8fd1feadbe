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

from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopoDS import TopoDS

from medax.cad.simplify.groups import Group, build_groups
from medax.cad.simplify.medial import Medial, medial_curve
from medax.cad.simplify.occ import count, diagonal, shape_map, small_list
from medax.cad.simplify.rebuild import build_solid
from medax.cad.simplify.specs import BlendInput, FilletSpec
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
    _keep_next_to_corners(work, blends, medials, kept)
    say(f"{len(medials)} fillets with a medial curve, {len(kept)} kept so far")
    specs = {s.face: s for s in blends.fillets if s.face in medials}
    surfaces = _surfaces(specs, medials, fmap, emap, kept, btol)
    say(f"{len(specs)} fillets with exact merged surfaces on {len(surfaces)} faces")

    def attempt(sel: dict[int, FilletSpec]) -> _Attempt | str:
        return _attempt(work, sel, medials, surfaces, fmap, diag, vol0, tol, say)

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
    removed = sorted(specs) if result is not None else []
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
        medial_error=max((medials[f].error for f in removed), default=0.0),
        notes=notes,
    )


def _keep_next_to_corners(shape, blends, medials, kept) -> None:  # type: ignore[no-untyped-def]
    """Fillets sharing an edge with a refused blend (corner blends) are kept too: their
    medial curves would have to end at the corner's centre (not supported)."""
    from medax.cad.simplify.specs import edge_face_map

    refused = {f for f, _ in blends.refused}
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
            kept[spec.face] = f"meets corner blend {min(near)} (kept): not supported"


def _halves_of(specs: dict[int, FilletSpec]) -> dict[int, list[tuple[int, int]]]:
    """supporting face -> [(fillet face, smooth edge index)]."""
    out: dict[int, list[tuple[int, int]]] = {}
    for s in specs.values():
        for e, sup in zip(s.smooth_edges, s.supporting, strict=True):
            out.setdefault(sup, []).append((s.face, e))
    return out


def _surfaces(specs, medials, fmap, emap, kept, btol) -> dict[int, MergedSurface]:  # type: ignore[no-untyped-def]
    """Merged surface per supporting face; fillets of faces without one move to ``kept``."""
    while True:
        surfaces: dict[int, MergedSurface] = {}
        failed = False
        for sup, hs in _halves_of(specs).items():
            halves = [
                Half(
                    TopoDS.Face(fmap.FindKey(f + 1)),
                    medials[f],
                    TopoDS.Edge(emap.FindKey(e + 1)),
                )
                for f, e in hs
            ]
            try:
                ms = merged_surface(TopoDS.Face(fmap.FindKey(sup + 1)), halves, btol)
            except (ValueError, RuntimeError) as err:  # OCCT construction failures
                ms = f"surface construction failed: {err}"
            if isinstance(ms, str):
                for f, _ in hs:
                    kept.setdefault(f, f"supporting face {sup}: {ms}")
                    specs.pop(f, None)
                failed = True
                break
            surfaces[sup] = ms
        if not failed:
            return surfaces


def _attempt(work, sel, medials, surfaces, fmap, diag, vol0, tol, say) -> _Attempt | str:  # type: ignore[no-untyped-def]
    try:
        say(f"splitting {len(sel)} fillets along their medial curves")
        split = split_along(work, [medials[f].edge for f in sel])
        groups = build_groups(split, {f: s.supporting for f, s in sel.items()})
        say(f"rebuilding: {len(groups)} faces")
        used = {g.support: surfaces[g.support].surface for g in groups if g.support is not None}
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
    for g, face in zip(groups, faces, strict=True):
        if g.support is None:
            continue
        old = [TopoDS.Face(split.face_map.FindKey(k + 1)) for k in g.members]
        dev = max(dev, *deviation(old, face, n=DEVIATION_SAMPLES, enough=1e-3 * tol * diag))
    if dev > tol * diag:
        return f"surface deviation {dev / diag:.2e} x diagonal (> {tol:g})"
    halves_origin = {g.id: [split.origin[k] for k in g.halves] for g in groups}
    kinds = {g.id: surfaces[g.support].kind for g in groups if g.support is not None}
    return _Attempt(shape, groups, faces, dev, vol0 * (1 + dv), split.origin, halves_origin, kinds)


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
