"""Checks of numbers the package's functions share (an internal helper module)."""

from __future__ import annotations

import math

from ..errors import InputError


def finite_positive(name: str, value: float) -> float:
    """``value`` as a float, refused with one :class:`InputError` line naming ``name``
    unless it is a finite number > 0."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} = {value!r}: must be a number") from None
    if not (math.isfinite(x) and x > 0):
        raise InputError(f"{name} = {value!r}: must be a finite number > 0")
    return x
