"""Routes: the longitudinal terrain profile along the path a vehicle will drive.

A :class:`Route` holds the validated arrays (distance, elevation, optional speed limit);
:func:`profileopt.io.read_route` reads one from a route file (the format is described
there). Every problem is one :class:`~profileopt.errors.InputError` line.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError
from ..terrain.assumed import AssumedRoughness

if TYPE_CHECKING:
    from .vehicle import Vehicle

__all__ = ["Route", "validate_route_arrays", "path_distance_m", "with_assumed_roughness", "MAX_ABS_ELEVATION_M",
           "MAX_ELEVATION_STEP_M", "MIN_SPEED_LIMIT_MPS"]

#: Elevations beyond this (m) are not on the Earth's surface: almost surely a unit mistake.
MAX_ABS_ELEVATION_M = 10_000.0
#: A jump between consecutive samples larger than this (m) is not terrain a vehicle drives.
MAX_ELEVATION_STEP_M = 100.0
#: A speed limit below this (m/s) is slower than any vehicle drives (the smallest top speed a
#: vehicle file may give): almost surely a unit mistake.
MIN_SPEED_LIMIT_MPS = 0.01


@dataclasses.dataclass(frozen=True, eq=False)
class Route:
    """A validated longitudinal terrain profile.

    Attributes
    ----------
    s_m : numpy.ndarray, shape (M,)
        Distance along the path (m), strictly increasing, M >= 2.
    z_m : numpy.ndarray, shape (M,)
        Elevation (m).
    speed_limit_mps : numpy.ndarray, shape (M,), or None
        Speed cap at each sample (m/s), > 0; None if the file has none.
    source : str
        Where the route came from (file name), used in messages.
    notes : tuple of str
        Remarks made while reading (ignored columns), for the user to see.
    x_m, y_m : numpy.ndarray, shape (M,), or None
        The path in the horizontal plane (m), for a route given as ``x,y,z``: its turns
        (:mod:`profileopt.terrain.geometry`). None for a route given as ``s,z`` (a straight path).
        Given, s must be the cumulative horizontal distance between the points.
    assumed_roughness : AssumedRoughness or None
        The roughness assumed for the route (an ISO 8608 class or an RI) when its elevation
        cannot measure it (a DEM or GPS profile): every roughness window then has that RI
        (docs/paper-notes.md, "Assumed roughness: ISO 8608 classes"). None: measured from z.
    """

    s_m: np.ndarray
    z_m: np.ndarray
    speed_limit_mps: np.ndarray | None = None
    source: str = "route"
    notes: tuple[str, ...] = ()
    x_m: np.ndarray | None = None
    y_m: np.ndarray | None = None
    assumed_roughness: AssumedRoughness | None = None

    def __post_init__(self) -> None:
        if self.assumed_roughness is not None and not isinstance(self.assumed_roughness, AssumedRoughness):
            raise InputError(f"{self.source}: assumed_roughness must be an AssumedRoughness (or None), got "
                             f"{type(self.assumed_roughness).__name__}")
        s = np.ascontiguousarray(self.s_m, dtype=float)
        z = np.ascontiguousarray(self.z_m, dtype=float)
        object.__setattr__(self, "s_m", s)
        object.__setattr__(self, "z_m", z)
        if s.ndim != 1 or z.shape != s.shape:
            raise InputError(f"{self.source}: s and z must be 1-D arrays of the same length")
        if s.size < 2:
            raise InputError(f"{self.source}: a route needs at least 2 samples, got {s.size}; add rows")
        limit = None
        if self.speed_limit_mps is not None:
            limit = np.ascontiguousarray(self.speed_limit_mps, dtype=float)
            if limit.shape != s.shape:
                raise InputError(f"{self.source}: speed_limit_mps has shape {limit.shape} but s has {s.shape}; "
                                 "give one speed limit per sample")
            object.__setattr__(self, "speed_limit_mps", limit)
        if (self.x_m is None) != (self.y_m is None):
            raise InputError(f"{self.source}: give both x_m and y_m (the path in the horizontal plane) or neither")
        if self.x_m is not None:
            for name in ("x_m", "y_m"):
                col = np.ascontiguousarray(getattr(self, name), dtype=float)
                if col.shape != s.shape or not np.all(np.isfinite(col)):
                    raise InputError(f"{self.source}: {name} must hold one finite coordinate (m) per sample")
                object.__setattr__(self, name, col)
        lines = np.arange(s.size)  # sample indices, used when no file lines are known
        validate_route_arrays(self.source, s, z, limit, lines, "sample")

    @property
    def length_m(self) -> float:
        """Length of the route s[-1] - s[0] (m)."""
        return float(self.s_m[-1] - self.s_m[0])


def path_distance_m(x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
    """Distance along a polyline in the plane from its first point: the cumulative length of
    its straight pieces, the ``s`` of a route given as ``x,y,z``.

    Parameters
    ----------
    x_m, y_m : numpy.ndarray, shape (M,)
        The polyline's points (m).

    Returns
    -------
    numpy.ndarray, shape (M,)
        s (m), from 0.
    """
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(y_m, dtype=float)
    return np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])


def validate_route_arrays(source: str, s: np.ndarray, z: np.ndarray, limit: np.ndarray | None,
                          where: np.ndarray, what: str) -> None:
    """Check a route's arrays; every problem is one line naming row ``where[i]``.

    Parameters
    ----------
    source : str
        The route's name (file), for messages.
    s : numpy.ndarray, shape (M,)
        Distance along the path (m); must be finite and increase strictly.
    z : numpy.ndarray, shape (M,)
        Elevation (m); finite, within +-MAX_ABS_ELEVATION_M, steps within MAX_ELEVATION_STEP_M.
    limit : numpy.ndarray, shape (M,), or None
        Speed limit at each sample (m/s), > 0.
    where : numpy.ndarray of int, shape (M,)
        The file line (or sample index) of each row, for messages.
    what : str
        What ``where`` counts: ``"line"`` or ``"sample"``.

    Raises
    ------
    InputError
        The first problem found.
    """
    for name, col in (("s", s), ("z", z)) + ((("speed_limit", limit),) if limit is not None else ()):
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:
            i = bad[0]
            raise InputError(f"{source}: {what} {where[i]}: {name} = {col[i]} is not a finite number; "
                             "remove the row or give a number")
    ds = np.diff(s)
    bad = np.flatnonzero(ds <= 0)
    if bad.size:
        i = bad[0] + 1
        kind = "repeats" if ds[i - 1] == 0 else "decreases"
        step = float(np.spacing(abs(s[i])))
        if step >= 1e-4:  # the numbers, not the file, lose the steps: 1e15 keeps only 0.125 m
            raise InputError(f"{source}: {what} {where[i]}: s = {s[i]:g} m {kind}: numbers this large keep "
                             f"distances only to {step:g} m in double precision; give s from the start of the "
                             "route (subtract the first value)")
        raise InputError(f"{source}: {what} {where[i]}: s = {s[i]:g} m {kind} (previous {s[i - 1]:g} m); "
                         "s must increase strictly, so sort the rows or drop duplicates")
    bad = np.flatnonzero(np.abs(z) > MAX_ABS_ELEVATION_M)
    if bad.size:
        i = bad[0]
        raise InputError(f"{source}: {what} {where[i]}: z = {z[i]:g} m is beyond +-{MAX_ABS_ELEVATION_M:g} m; "
                         "elevations are in metres (were they given in millimetres?)")
    dz = np.abs(np.diff(z))
    bad = np.flatnonzero(dz > MAX_ELEVATION_STEP_M)
    if bad.size:
        i = bad[0] + 1
        raise InputError(f"{source}: {what} {where[i]}: z jumps by {dz[i - 1]:g} m from the previous sample; "
                         f"steps above {MAX_ELEVATION_STEP_M:g} m are not drivable terrain (check the units)")
    if limit is not None:
        bad = np.flatnonzero(limit <= 0)
        if bad.size:
            i = bad[0]
            raise InputError(f"{source}: {what} {where[i]}: speed_limit = {limit[i]:g} m/s must be > 0; "
                             "give a positive limit in m/s")
        bad = np.flatnonzero(limit < MIN_SPEED_LIMIT_MPS)
        if bad.size:
            i = bad[0]
            raise InputError(f"{source}: {what} {where[i]}: speed_limit = {limit[i]:g} m/s is below "
                             f"{MIN_SPEED_LIMIT_MPS:g} m/s, slower than any vehicle drives; give the limit in m/s "
                             "(was it given in another unit?)")


def with_assumed_roughness(route: "Route", vehicle: "Vehicle", *, window_m: float, seed: int) -> tuple["Route", str]:
    """The route ``verify`` (and the planner's simulation gate) drives when its roughness was
    assumed: its elevation plus a seeded
    random ISO 8608 profile whose RMS window roughness is the assumed one, and a note
    saying so.

    Parameters
    ----------
    route : Route
        A route with ``assumed_roughness``.
    vehicle : Vehicle
        Supplies the ground clearance h (m).
    window_m : float
        The roughness window length W the profile was planned with (m).
    seed : int
        Seed (>= 0) of the random phases.

    Returns
    -------
    route : Route
        The same samples, elevation ``z_m + realisation``, the same assumed roughness.
    note : str
        One line for the user: the class (or RI), the seed, the band and the RMS.
    """
    assumed = route.assumed_roughness
    h = vehicle.ground_clearance_m
    added = assumed.realisation_m(route.s_m, clearance_m=h, window_m=window_m, seed=seed)
    n_min, n_max = assumed.realisation_band_cpm(route.s_m)
    ri = assumed.ri_for(clearance_m=h, window_m=window_m)
    shape = f"ISO 8608 class {assumed.road_class}" if assumed.road_class else "ISO 8608 (class C's shape)"
    note = (f"roughness assumed ({assumed.label}): simulated on the route's elevation plus a random {shape} "
            f"profile, seed {seed}, {n_min:g} to {n_max:.3g} cycles/m, RMS {1e3 * ri * h:.3g} mm over {window_m:g} m "
            f"windows (RI {ri:.4g}); another seed drives other ground of that roughness")
    return dataclasses.replace(route, z_m=route.z_m + added), note
