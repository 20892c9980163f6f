"""Deprecated module: the readers of measured terrain are in :mod:`profileopt.io` now.

``from profileopt.realdata import read_las`` keeps working for one release, with a
``DeprecationWarning`` naming the new place.
"""

from __future__ import annotations

import warnings

_MOVED = ("read_opencrg", "read_xy_profile", "LasHeader", "PointCloud", "read_las", "LAS_GROUND")


def __getattr__(name: str) -> object:
    if name not in _MOVED:
        raise AttributeError(f"module 'profileopt.realdata' has no attribute {name!r}")
    from . import io

    warnings.warn(f"profileopt.realdata.{name} is deprecated; use profileopt.io.{name}", DeprecationWarning,
                  stacklevel=2)
    return getattr(io, name)
