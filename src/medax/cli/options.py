"""Checks of numeric options shared by the subcommands (one-line InputError each)."""

from __future__ import annotations

import math

from medax.errors import InputError


def check_tol(value: float, option: str, floor: float, zero_ok: bool = False) -> float:
    """``value`` if it is a finite positive number (or 0 with ``zero_ok``) not below
    ``floor``, the smallest relative tolerance double precision reaches for this option."""
    if not math.isfinite(value):
        raise InputError(f"{option} {value}: must be a finite number")
    if value == 0.0 and zero_ok:
        return value
    if value <= 0.0:
        need = "non-negative" if zero_ok else "positive"
        raise InputError(f"{option} {value:g}: must be {need}")
    if value < floor:
        raise InputError(
            f"{option} {value:g}: below {floor:g}, the smallest tolerance double precision "
            "reaches here (relative to the diagonal)"
        )
    return value
