"""Profile files: the CSV that ``profileopt plan -o`` writes and ``profileopt verify`` reads.

One ``# profileopt profile: key=value ...`` comment line records what the profile was
planned with (vehicle, model, limits), then the header :data:`PROFILE_COLUMNS` and one row
per segment boundary. Numbers are written with 17 significant digits (``%.17g``), so
reading a file back gives the same floats and the same input gives the same bytes.
"""

from __future__ import annotations

import os

import numpy as np

from ..core.binding import BINDING_NAMES
from ..core.profile import BASE_COLUMNS, PROFILE_COLUMNS, Profile
from ..errors import InputError
from ..physics.forces import DEFAULT_MODEL, MODELS
from .atomic import atomic_write
from .table import read_table

__all__ = ["read_profile", "write_profile", "PROFILE_COLUMNS"]

_SETTINGS_PREFIX = "# profileopt profile:"


def _format_setting(value: object) -> str:
    if isinstance(value, float):
        return repr(value)
    return str(value).replace(" ", "_")


def write_profile(profile: Profile, path: str | os.PathLike) -> None:
    """Write a profile CSV atomically: a settings comment line, the header, one row per boundary.

    Parameters
    ----------
    profile : Profile
        The profile (its :attr:`~Profile.settings` and :attr:`~Profile.status` go into the
        comment line).
    path : str or os.PathLike
        Output file; it appears only when the whole file is written.
    """
    columns = profile.columns()
    # one '%' format per row over Python floats and strings, as numpy.savetxt formats them but
    # without its per-row writes (a fifth faster); binding is the one text column
    cells = [[str(label) for label in values] if name == "binding" else np.asarray(values, dtype=float).tolist()
             for name, values in columns.items()]
    row = ",".join("%s" if name == "binding" else "%.17g" for name in columns) + "\n"
    meta = " ".join(f"{k}={_format_setting(v)}" for k, v in profile.settings.items())
    with atomic_write(path) as handle:
        handle.write(f"{_SETTINGS_PREFIX} {meta} status={profile.status.replace(' ', '_')}\n")
        handle.write(",".join(columns) + "\n")
        handle.write("".join(map(row.__mod__, zip(*cells))))


def read_profile(path: str | os.PathLike) -> Profile:
    """Read a profile CSV written by :func:`write_profile` (``profileopt plan -o``).

    Parameters
    ----------
    path : str or os.PathLike
        The profile file.

    Returns
    -------
    Profile
        ``status`` is ``"read"``; ``settings`` holds the comment line's values as text.

    Raises
    ------
    InputError
        Missing file, wrong header, non-numeric or non-finite cells, fewer than 2 rows,
        s not increasing, a negative speed or an unknown model.
    """
    table = read_table(path, "profile file", header_example=",".join(PROFILE_COLUMNS),
                       empty_fix="write one with 'profileopt plan -o'")
    name = table.source
    settings: dict[str, object] = {}
    settings_line = 1
    for number, line in table.comments:
        if line.startswith(_SETTINGS_PREFIX):
            settings_line = number
            for item in line[len(_SETTINGS_PREFIX):].split():
                key, _, value = item.partition("=")
                settings[key] = value
    if table.header not in (PROFILE_COLUMNS, BASE_COLUMNS):
        raise InputError(f"{name}: line {table.header_line}: header must be {','.join(PROFILE_COLUMNS)}; "
                         f"got {','.join(table.header)} (write the profile with 'profileopt plan -o')")
    full = table.header == PROFILE_COLUMNS
    numeric = PROFILE_COLUMNS[:-1] if full else BASE_COLUMNS
    values = table.numbers(range(len(numeric)))
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
    if model not in MODELS:
        raise InputError(f"{name}: line {settings_line}: model={model} is unknown; it must be one of "
                         f"{', '.join(MODELS)}")
    extra: dict[str, object] = {}
    if full:
        labels = np.array([row.rsplit(",", 1)[1].strip() for row in table.rows], dtype=object)
        bad = np.flatnonzero(~np.isin(labels, BINDING_NAMES))
        if bad.size:
            i = bad[0]
            raise InputError(f"{name}: line {numbers[i]}: binding = '{labels[i]}' is not one of "
                             f"{', '.join(BINDING_NAMES)}; write the profile with 'profileopt plan -o'")
        extra["binding"] = labels
    return Profile(**{column: values[:, i] for i, column in enumerate(numeric)}, model=model,
                   settings=settings, **extra)
