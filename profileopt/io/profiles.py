"""Profile files: the CSV that ``profileopt plan -o`` writes and ``profileopt verify`` reads.

One ``# profileopt profile: key=value ...`` comment line records what the profile was
planned with (vehicle, model, limits), then the header and one row per segment boundary:
:data:`PROFILE_COLUMNS`, then the route's own ``x_m, y_m, z_m`` at each boundary (``z_m``
alone for an ``s,z`` route; :data:`COORDINATE_COLUMNS`), so a plan can be mapped without
joining it to its route. A value of the settings line that holds a space, a quote or a
character outside printable ASCII (a vehicle file ``my veh.toml``) is written as a JSON
string (``vehicle="/home/me/my veh.toml"``); the vehicle is recorded as an absolute path
(or a bundled name) with the SHA-256 of its bytes (``vehicle_sha256``), so that ``verify``
finds the same file from any folder and refuses another one.

Numbers are rounded to what they mean (:data:`COLUMN_FORMATS`): the boundaries ``s_m``
exactly (the shortest text that reads back as the same float: they are positions of the
route's samples, whose segments verify finds again), the speeds to 12 significant digits
(verify differentiates them twice, into accelerations and jerks over segments as short as
0.1 m, and judges those within :data:`profileopt.defaults.LIMIT_RTOL`; 9 digits put a
planned profile up to 3.6e-6 over a limit there), every other number to 9. The same input
gives the same bytes.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.binding import BINDING_NAMES
from ..core.profile import BASE_COLUMNS, PROFILE_COLUMNS, Profile
from ..core.vehicle import names_vehicle_file
from ..errors import InputError
from ..defaults import DEFAULT_MODEL, PLAN_MODEL_KEYS
from .atomic import atomic_write
from .table import read_table

if TYPE_CHECKING:
    from ..core.route import Route

__all__ = ["read_profile", "write_profile", "PROFILE_COLUMNS", "COORDINATE_COLUMNS", "COLUMN_FORMATS",
           "recorded_vehicle", "vehicle_file_sha256", "SETTINGS_PREFIX"]

#: The comment line that records what a profile was planned with.
SETTINGS_PREFIX = "# profileopt profile:"
#: The route's coordinates at each boundary (m), after :data:`PROFILE_COLUMNS`: ``x_m, y_m,
#: z_m`` for a route with x, y, ``z_m`` for an ``s,z`` route.
COORDINATE_COLUMNS = ("x_m", "y_m", "z_m")
#: The %-format of each column (others: ``%.9g``): see the module's notes.
COLUMN_FORMATS = {"s_m": "%r", "speed_mps": "%.12g", "binding": "%s"}
_DEFAULT_FORMAT = "%.9g"
#: The headers a profile file may have: files written before turns and hills, before the
#: coordinates, and now (with z, or with x, y, z).
_HEADERS = (BASE_COLUMNS, PROFILE_COLUMNS, PROFILE_COLUMNS + ("z_m",), PROFILE_COLUMNS + COORDINATE_COLUMNS)
#: A settings item: key=value, the value a JSON string or text without white space.
_ITEM = re.compile(r'([^\s=]+)=("(?:[^"\\]|\\.)*"|\S*)')
_PLAIN_VALUE = re.compile(r"[!#-~]*")  # printable ASCII without space and '"'


def vehicle_file_sha256(reference: str) -> tuple[str, str]:
    """The file a vehicle reference names and the SHA-256 of its bytes (hex).

    Parameters
    ----------
    reference : str
        A bundled vehicle name (``"atv"``) or the path of a ``.toml`` file, as
        :func:`profileopt.load_vehicle` takes it.

    Returns
    -------
    (str, str)
        The file (a bundled name's file in the package) and its SHA-256.

    Raises
    ------
    InputError
        No bundled vehicle of that name, or the file cannot be read.
    """
    from ..core.vehicle import load_vehicle
    from . import inputs

    path = Path(load_vehicle(reference).name) if not names_vehicle_file(reference) else Path(reference)
    # as load_vehicle reads it: a regular file of at most MAX_VEHICLE_BYTES (never a FIFO, /dev/zero)
    data = inputs.read_input(path, "vehicle file", inputs.MAX_VEHICLE_BYTES)
    return str(path), hashlib.sha256(data).hexdigest()


def recorded_vehicle(settings: dict) -> dict[str, object]:
    """The vehicle entries a settings line records: an absolute path (a bundled name as it is)
    and the SHA-256 of the file's bytes.

    Parameters
    ----------
    settings : dict
        A profile's settings; ``settings["vehicle"]`` is a bundled name, a path (relative to
        the current folder) or ``"unnamed"``.

    Returns
    -------
    dict
        ``{"vehicle": ..., "vehicle_sha256": ...}`` to update the settings with (empty for an
        unnamed vehicle; the settings' own ``vehicle_sha256`` is kept when they hold one).
    """
    reference = str(settings.get("vehicle", ""))
    if reference in ("", "unnamed"):
        return {}
    absolute = os.path.abspath(reference) if names_vehicle_file(reference) else reference
    if "vehicle_sha256" in settings:
        return {"vehicle": absolute, "vehicle_sha256": str(settings["vehicle_sha256"])}
    try:
        _, digest = vehicle_file_sha256(reference)
    except InputError:
        return {"vehicle": absolute}  # gone since it was planned with: verify says so
    return {"vehicle": absolute, "vehicle_sha256": digest}


def _format_setting(value: object) -> str:
    text = repr(value) if isinstance(value, float) else str(value)
    return text if text and _PLAIN_VALUE.fullmatch(text) else json.dumps(text)


def _parse_setting(value: str) -> str:
    if value[:1] == '"':
        try:
            return str(json.loads(value))
        except ValueError:
            return value
    return value


def write_profile(profile: Profile, path: str | os.PathLike, route: "Route | None" = None) -> None:
    """Write a profile CSV atomically: a settings comment line, the header, one row per boundary.

    Parameters
    ----------
    profile : Profile
        The profile (its :attr:`~Profile.settings` and :attr:`~Profile.status` go into the
        comment line; the vehicle as an absolute path or bundled name with its SHA-256,
        :func:`recorded_vehicle`).
    path : str or os.PathLike
        Output file; it appears only when the whole file is written.
    route : Route, optional
        The route it was planned on: its ``x_m, y_m, z_m`` (or ``z_m``) at each boundary,
        interpolated linearly between its samples, are written after the profile's columns.
    """
    columns = dict(profile.columns())
    if route is not None:
        s = np.asarray(profile.s_m, dtype=float)
        names = COORDINATE_COLUMNS if route.x_m is not None else ("z_m",)
        for name in names:
            columns[name] = np.interp(s, route.s_m, getattr(route, name))
    # one '%' format per row over Python floats and strings, as numpy.savetxt formats them but
    # without its per-row writes (a fifth faster); binding is the one text column; + 0.0: no -0
    cells = [[str(label) for label in values] if name == "binding" else (np.asarray(values, dtype=float) + 0.0).tolist()
             for name, values in columns.items()]
    row = ",".join(COLUMN_FORMATS.get(name, _DEFAULT_FORMAT) for name in columns) + "\n"
    vehicle = recorded_vehicle(profile.settings)  # vehicle_sha256 right after the vehicle
    settings = {}
    for key, value in profile.settings.items():
        if key not in ("vehicle_sha256", "status"):
            settings[key] = vehicle.pop(key, value)
        if key == "vehicle":
            settings |= vehicle
    # a profile read from a file keeps the status it was planned with
    status = profile.settings.get("status", profile.status) if profile.status == "read" else profile.status
    meta = " ".join(f"{k}={_format_setting(v)}" for k, v in (settings | {"status": status}).items())
    with atomic_write(path) as handle:
        handle.write(f"{SETTINGS_PREFIX} {meta}\n")
        handle.write(",".join(columns) + "\n")
        handle.write("".join(map(row.__mod__, zip(*cells))))


def _settings(name: str, comments) -> tuple[dict[str, object], int]:
    """The settings line's values as text, and its line number (1 when there is none)."""
    settings: dict[str, object] = {}
    settings_line = 0
    for number, line in comments:
        if not line.startswith(SETTINGS_PREFIX):
            continue
        if settings_line:
            raise InputError(f"{name}: line {number}: a second settings line ('{SETTINGS_PREFIX} ...'; the first is "
                             f"line {settings_line}); a profile records one, so remove one of them or plan again")
        settings_line = number
        text = line[len(SETTINGS_PREFIX):]
        for match in _ITEM.finditer(text):
            key, value = match.group(1), match.group(2)
            if key in settings:
                raise InputError(f"{name}: line {number}: the settings line gives {key} twice ({settings[key]} and "
                                 f"{_parse_setting(value)}); remove one of them or plan again")
            settings[key] = _parse_setting(value)
    return settings, settings_line or 1


def read_profile(path: str | os.PathLike) -> Profile:
    """Read a profile CSV written by :func:`write_profile` (``profileopt plan -o``).

    Files written before the coordinates (or before turns and hills) are read too.

    Parameters
    ----------
    path : str or os.PathLike
        The profile file.

    Returns
    -------
    Profile
        ``status`` is ``"read"``; ``settings`` holds the comment line's values as text.
        The coordinate columns are not part of a :class:`Profile` (they are the route's).

    Raises
    ------
    InputError
        Missing file, wrong header, non-numeric or non-finite cells, fewer than 2 rows,
        s not increasing, a negative speed, an unknown model, or a second settings line (or
        a key given twice in it).
    """
    table = read_table(path, "profile file", header_example=",".join(PROFILE_COLUMNS),
                       empty_fix="write one with 'profileopt plan -o'")
    name = table.source
    settings, settings_line = _settings(name, table.comments)
    if table.header not in _HEADERS:
        raise InputError(f"{name}: line {table.header_line}: header must be {','.join(PROFILE_COLUMNS)} (then "
                         f"{','.join(COORDINATE_COLUMNS)} or z_m, optionally); got {','.join(table.header)} (write "
                         "the profile with 'profileopt plan -o')")
    full = table.header != BASE_COLUMNS
    numeric = PROFILE_COLUMNS[:-1] if full else BASE_COLUMNS
    binding_at = len(PROFILE_COLUMNS) - 1
    used = [i for i in range(len(table.header)) if not (full and i == binding_at)]
    values = table.numbers(used)
    numbers = table.line_numbers
    if len(values) < 2:
        raise InputError(f"{name}: {len(values)} data row(s); a profile needs at least 2 (the start and the end "
                         "of the route)")
    bad = np.flatnonzero(np.diff(values[:, 0]) <= 0)
    if bad.size:
        i = bad[0] + 1
        raise InputError(f"{name}: line {numbers[i]}: s_m = {values[i, 0]:g} m does not increase (previous "
                         f"{values[i - 1, 0]:g} m); s_m must increase strictly, so sort the rows or drop duplicates")
    bad = np.flatnonzero(values[:, 1] < 0)
    if bad.size:
        i = bad[0]
        raise InputError(f"{name}: line {numbers[i]}: speed_mps = {values[i, 1]:g} m/s is negative; "
                         "speeds must be >= 0")
    model = str(settings.get("model", DEFAULT_MODEL))
    if model not in PLAN_MODEL_KEYS:
        raise InputError(f"{name}: line {settings_line}: model={model} is unknown; it must be one of "
                         f"{', '.join(PLAN_MODEL_KEYS)}")
    extra: dict[str, object] = {}
    if full:
        labels = np.array([row.split(",")[binding_at].strip() for row in table.rows], dtype=object)
        bad = np.flatnonzero(~np.isin(labels, BINDING_NAMES))
        if bad.size:
            i = bad[0]
            raise InputError(f"{name}: line {numbers[i]}: binding = '{labels[i]}' is not one of "
                             f"{', '.join(BINDING_NAMES)}; write the profile with 'profileopt plan -o'")
        extra["binding"] = labels
    return Profile(**{column: values[:, i] for i, column in enumerate(numeric)}, model=model,
                   settings=settings, **extra)
