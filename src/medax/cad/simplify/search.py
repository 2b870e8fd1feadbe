"""The search for the fillets that rebuild together, and the fillet relations it uses.

When the rebuild with every fillet fails, :func:`isolate` finds the failing fillets
themselves by bisection: halves of the fillets, in cluster order, are added to what already
rebuilds; a half that fails is halved again down to the single fillet, which is kept with
its own reason. Bookkeeping over face indices only: the rebuild is the caller's ``attempt``.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterable, Sequence
from typing import TypeVar

import numpy as np

from medax.cad.simplify.specs import FilletSpec

log = logging.getLogger(__name__)

#: What a successful ``attempt`` returns (the pipeline's rebuilt and validated solid).
A = TypeVar("A")


class Failure(str):
    """A failed attempt's reason, with the fillets it is traced to (``blamed``: those of the
    new faces that failed their own check); empty when only the whole attempt failed."""

    blamed: frozenset[int]

    def __new__(cls, why: str, blamed: Iterable[int] = ()) -> Failure:
        obj = super().__new__(cls, why)
        obj.blamed = frozenset(blamed)
        return obj


def volume_blame(shares: Sequence[float] | np.ndarray, change: float, tol: float) -> list[int]:
    """The groups to leave out so that a volume change within ``tol`` remains: indices
    into ``shares`` (each changed group's own relative volume change), taken greedily by
    the largest share of the sign of ``change`` (the measured total) until the rest is
    within ``tol / 2``. Empty when the shares do not account for the measured change (their
    sum more than half of it away), or when leaving all of them out would be needed."""
    s = np.asarray(shares, dtype=float)
    if s.size == 0 or not np.isfinite(s).all() or abs(s.sum() - change) > 0.5 * abs(change):
        return []
    rest, out = float(s.sum()), []
    for i in np.argsort(-np.sign(change) * s, kind="stable").tolist():
        if abs(rest) <= 0.5 * tol or np.sign(s[i]) != np.sign(change):
            break
        out.append(i)
        rest -= float(s[i])
    return out if abs(rest) <= 0.5 * tol and len(out) < s.size else []


def riders(specs: dict[int, FilletSpec]) -> dict[int, list[int]]:
    """Simplified fillet -> the simplified fillets that ride on it (have it as support)."""
    out: dict[int, list[int]] = {}
    for s in specs.values():
        for base in s.supporting:
            if base in specs:
                out.setdefault(base, []).append(s.face)
    return out


def halves_of(specs: dict[int, FilletSpec]) -> dict[int, list[tuple[int, int]]]:
    """supporting face -> [(fillet face, smooth edge index)]."""
    out: dict[int, list[tuple[int, int]]] = {}
    for s in specs.values():
        for e, sup in zip(s.smooth_edges, s.supporting, strict=True):
            out.setdefault(sup, []).append((s.face, e))
    return out


def clusters(specs: dict[int, FilletSpec]) -> list[list[int]]:
    """Fillets linked through shared supporting faces (they must be merged together)."""
    by_sup = halves_of(specs)
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
                if sup in specs:  # x rides on fillet sup
                    stack.append(sup)
            stack.extend(y for y, _ in by_sup.get(x, []))  # fillets riding on x
        out.append(comp)
    return out


def isolate(
    specs: dict[int, FilletSpec],
    attempt: Callable[[dict[int, FilletSpec]], A | str],
    kept: dict[int, str],
    say: Callable[[str], None],
    deadline: float,
    why: str,
    together: Sequence[set[int]] = (),
) -> tuple[A | None, dict[int, FilletSpec]]:
    """The fillets that rebuild together after the rebuild with all of ``specs`` failed
    (for the reason ``why``), and their (last successful) attempt.

    Fillets are taken in cluster order (linked fillets next to each other) and added in
    halves to the accepted set: a half that rebuilds with everything accepted so far is
    accepted, one that fails is halved again, down to the single fillet, which is kept with
    the reason of its failure. So one failing fillet costs about 2 log2(n) rebuilds and its
    neighbours still go, and the result is always an attempt that passed as a whole.

    A failure traced to some of the fillets tried (:class:`Failure` ``blamed``: a new face
    that failed its own check) is not bisected: the others are tried without them, then the
    blamed ones on their own (one blamed fillet is kept at once; several are halved at once
    when all the others were accepted, since together they would repeat the failed
    attempt). On a 555-face part with 214 fillets, bisection alone ran out of time with half
    of them untried.

    ``together``: sets of fillets that go together or not at all (a chain of tangent
    fillets, :mod:`.chains`): each is one unit of the bisection."""
    order = [f for c in clusters(specs) for f in c]
    unit_of = {f: frozenset(t) & set(specs) for t in together for f in t if f in specs}
    units: list[tuple[int, ...]] = []
    placed: set[int] = set()
    for f in order:
        if f not in placed:
            u = tuple(sorted(unit_of.get(f, {f}), key=order.index))
            units.append(u)
            placed |= set(u)
    accepted: dict[int, FilletSpec] = {}
    best: A | None = None

    def keep(u: tuple[int, ...], why: str) -> None:
        for f in u:
            kept[f] = f"rebuild failed: {why}"
            say(f"fillet {f} kept: {why}")

    def rec(group: list[tuple[int, ...]], known: A | str | None = None) -> None:
        nonlocal best
        if not group:
            return
        fillets = [f for u in group for f in u]
        if time.process_time() > deadline:
            for f in fillets:
                kept[f] = "not tried alone: the time for finding the failing fillets ran out"
            return
        log.info("isolating: trying %d, %d/%d accepted", len(fillets), len(accepted), len(order))
        r = attempt({**accepted, **{f: specs[f] for f in fillets}}) if known is None else known
        if not isinstance(r, str):
            accepted.update({f: specs[f] for f in fillets})
            best = r
            say(f"{len(fillets)} more fillets go ({len(accepted)} of {len(order)} so far)")
            return
        hit: frozenset[int] = getattr(r, "blamed", frozenset()) & set(fillets)
        blamed = [u for u in group if set(u) & hit]
        if len(group) > 1 and known is None:
            traced = f", traced to {len(hit)} of them" if hit else ""
            n, m = len(fillets), len(accepted)
            say(f"{n} fillets tried with the {m} accepted failed{traced}: {r}")
        if len(group) == 1:
            keep(group[0], r)
        elif blamed and len(blamed) < len(group):
            before = set(accepted)
            others = [u for u in group if u not in blamed]
            rec(others)
            if len(blamed) == 1:
                keep(blamed[0], r)
            else:
                # with all the others accepted, the blamed ones together are the attempt
                # that failed: its result is known
                same = set(accepted) == before | {f for u in others for f in u}
                rec(blamed, r if same else None)
        else:
            rec(group[: len(group) // 2])
            rec(group[len(group) // 2 :])

    rec(units, why)  # the rebuild with all of them failed for the reason ``why``
    return best, accepted
