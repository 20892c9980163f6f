"""The one guard in front of every file the package reads.

:func:`read_input` refuses, with one line, a path that is not a regular file (``/dev/zero``,
``/dev/urandom`` and a terminal would be read until memory runs out, a FIFO without a writer
would block for ever: it is opened without blocking and refused) and a file above a stated
size, before reading it.

The size caps
-------------
Reading a route file takes about 13 bytes of memory per byte of it, most of it Python's
per-line strings (measured: a 39 MB file of 2.35 million ``s,z`` rows peaks at 0.49 GB, a
42 MB one at 0.54 GB); the cap :data:`MAX_TABLE_BYTES` (50 MB) keeps that near 0.65 GB.
Planning the route takes far more, growing with its samples, segments and travel time, not
with the file: ``profileopt plan`` estimates it before any work and refuses a route over its
``--max-memory`` (:mod:`profileopt.cli.memory`; 1.5 GB by default, about 600,000 samples at
0.05 m). A route made from a track (``profileopt route TRACK``, and ``plan TRACK`` before
that estimate) is checked before it is sampled: at most :func:`max_route_samples` samples
(909,090: 45 km at 0.05 m; :data:`MEMORY_PER_TRACK_SAMPLE` each in ``MAX_TABLE_BYTES`` x
:data:`MEMORY_PER_TABLE_BYTE`, 1 GB). Making the route needs less than that (measured with
``profileopt route``: 893,000 samples peak at 0.34 GB); without the cap a 130-byte track
spanning 500 km was cut into 10 million samples and ran out of memory after minutes.
A vehicle file is a dozen lines: 1 MB is generous. A LAS
or LAZ point cloud is checked against its own header, then decoded in chunks keeping only the
points near the track (at most 20 million, :data:`profileopt.io.las.MAX_CLOUD_POINTS`); a
GeoTIFF is read in the window around the track (at most 25 million cells,
:data:`profileopt.io.terrain_maps.MAX_GRID_CELLS`); an OpenCRG file is
read whole up to :data:`MAX_BINARY_BYTES`.
"""

from __future__ import annotations

import os
import stat

from ..errors import InputError

__all__ = ["read_input", "check_regular_input", "max_route_samples", "MAX_TABLE_BYTES", "MAX_BINARY_BYTES",
           "MAX_VEHICLE_BYTES", "MEMORY_PER_TABLE_BYTE", "MEMORY_PER_TRACK_SAMPLE"]

#: Largest route or profile file read (bytes); see the module's notes for the memory it needs.
MAX_TABLE_BYTES = 50_000_000
#: Largest binary terrain file read whole (OpenCRG; bytes): numbers, not lines, about 3 bytes
#: of memory per byte of file.
MAX_BINARY_BYTES = 500_000_000
#: Largest vehicle file read (bytes).
MAX_VEHICLE_BYTES = 1_000_000
#: Bytes of memory allowed per byte of the largest route file (with :data:`MAX_TABLE_BYTES`,
#: the 1 GB that bounds a route made from a track; see the module's notes).
MEMORY_PER_TABLE_BYTE = 20
#: Bytes of memory allowed per sample of a route made from a track (with
#: :data:`MEMORY_PER_TABLE_BYTE`, the cap :func:`max_route_samples`; making the route measured
#: about 0.4 kB per sample, planning it about 1.1 to 4 kB: :mod:`profileopt.cli.memory`).
MEMORY_PER_TRACK_SAMPLE = 1_100


def max_route_samples() -> int:
    """The most samples a route made from a track may have: as many as need the memory of the
    largest route file.

    Returns
    -------
    int
        :data:`MAX_TABLE_BYTES` x :data:`MEMORY_PER_TABLE_BYTE` // :data:`MEMORY_PER_TRACK_SAMPLE`
        as they are when called (909,090), so that raising the file cap from Python raises
        this one too.
    """
    return MAX_TABLE_BYTES * MEMORY_PER_TABLE_BYTE // MEMORY_PER_TRACK_SAMPLE


def _kind(mode: int) -> str:
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def _megabytes(n: int) -> str:
    return f"{n / 1e6:.3g} MB"


def _open_regular(path: str | os.PathLike, what: str) -> int:
    """Open ``path`` for reading without blocking (a FIFO) and check that it is a regular file."""
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise InputError(f"{path}: {what} not found; check the path") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a folder, not a {what}") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read the {what} ({exc})") from None
    try:
        mode = os.fstat(fd).st_mode
    except OSError as exc:  # pragma: no cover - fstat of an open descriptor
        os.close(fd)
        raise InputError(f"{path}: cannot read the {what} ({exc})") from None
    if stat.S_ISDIR(mode):
        os.close(fd)
        raise InputError(f"{path}: is a folder, not a {what}")
    if not stat.S_ISREG(mode):
        os.close(fd)
        raise InputError(f"{path}: is {_kind(mode)}, not a regular file; give the path of a {what}")
    return fd


def check_regular_input(path: str | os.PathLike, what: str) -> None:
    """Refuse ``path`` unless it is an existing regular file (for readers of large binary files).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What the file is, for messages ("LAS file").

    Raises
    ------
    InputError
        Missing, a folder, unreadable, or not a regular file (a device, FIFO or socket).
    """
    os.close(_open_regular(path, what))


def read_input(path: str | os.PathLike, what: str, max_bytes: int | None = None) -> bytes:
    """The bytes of a regular file of at most ``max_bytes``, or one line saying why not.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What the file is, for messages ("route file", "vehicle file").
    max_bytes : int, optional
        The largest size read (default: :data:`MAX_TABLE_BYTES` as it is when called).

    Returns
    -------
    bytes

    Raises
    ------
    InputError
        Missing, a folder, unreadable, not a regular file (a device, FIFO or socket), or
        larger than ``max_bytes``.
    """
    if max_bytes is None:
        max_bytes = MAX_TABLE_BYTES
    fd = _open_regular(path, what)
    with os.fdopen(fd, "rb") as handle:
        size = os.fstat(fd).st_size
        if size <= max_bytes:
            try:
                data = handle.read(max_bytes + 1)
            except OSError as exc:
                raise InputError(f"{path}: cannot read the {what} ({exc})") from None
            size = max(size, len(data))
    if size > max_bytes:
        raise InputError(f"{path}: the {what} is {_megabytes(size)}, larger than the {_megabytes(max_bytes)} a "
                         f"{what} may have here (see profileopt.io.inputs for the memory it needs); split it "
                         "into shorter files")
    return data
