"""Kept-blend reasons grouped for the report: numbers (face indices, measures) as ``N``."""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Iterable


def reason_kind(why: str) -> str:
    """A kept blend's reason with its numbers (face indices, measures) and lists of them
    replaced by ``N``: the key under which the report groups reasons."""
    one = re.sub(r"[-+]?\d+(\.\d+)?(e[-+]?\d+)?", "N", why)
    return re.sub(r"N(, N)+(, \.\.\.)?", "N", one)


def reason_counts(reasons: Iterable[str]) -> dict[str, int]:
    """How many kept blends have each :func:`reason_kind`, most frequent first."""
    counts = Counter(reason_kind(r) for r in reasons)
    return dict(counts.most_common())
