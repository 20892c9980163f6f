"""Atomic output files: a failed or interrupted run never leaves a half-written file."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import IO, Iterator

from ..errors import InputError

__all__ = ["atomic_write", "atomic_path", "check_output_path", "check_output_paths"]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def check_output_path(path: str | os.PathLike) -> Path:
    """Refuse, before any work is done, an output path that cannot be written.

    Commands call it for every output first, so that a run that would fail at its second
    output never writes its first one.

    Parameters
    ----------
    path : str or os.PathLike
        The file to be written; its folder must exist and be writable, and it must not
        itself be a folder.

    Returns
    -------
    pathlib.Path
        ``path`` as a :class:`~pathlib.Path`.

    Raises
    ------
    InputError
        The folder does not exist or is not writable, or the path is a folder.
    """
    target = Path(path)
    directory = target.parent if str(target.parent) else Path(".")
    if not directory.is_dir():
        what = "is a file, not a folder" if directory.exists() else "does not exist"
        raise InputError(f"{target}: {directory} {what}; create the folder or choose another path")
    if target.is_dir():
        raise InputError(f"{target}: is a folder; give the path of a file to write")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise InputError(f"{target}: cannot write in {directory} (permission denied); choose another path")
    return target


def check_output_paths(*paths: str | os.PathLike | None) -> None:
    """:func:`check_output_path` for every path given (``None``: that output is not wanted).

    Parameters
    ----------
    *paths : str or os.PathLike or None
        The output paths to check; None (or an empty string) is skipped.

    Raises
    ------
    InputError
        At the first path that cannot be written.
    """
    for path in paths:
        if path:
            check_output_path(path)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it onto ``path``.

    If the block raises, the temporary file is removed and ``path`` (and any good earlier
    file there) is left untouched. Use it for writers that want a file name (matplotlib's
    ``savefig``, C code generators); :func:`atomic_write` for text.

    Parameters
    ----------
    path : str or os.PathLike
        The file to create or replace; checked first with :func:`check_output_path`.

    Yields
    ------
    pathlib.Path
        A temporary file in the same folder as ``path``, to be written by the block.

    Raises
    ------
    InputError
        ``path`` cannot be written, or no temporary file can be made in its folder.
    """
    target = check_output_path(path)
    directory = target.parent
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=target.suffix or ".tmp", dir=directory)
    except OSError as exc:
        raise InputError(f"{target}: cannot write in {directory} ({exc.strerror}); choose another path") from None
    os.close(fd)
    os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; outputs get the usual permissions
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.replace(tmp_path, target)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike, newline: str = "\n") -> Iterator[IO[str]]:
    """Open a text file for writing that appears at ``path`` only if the block succeeds.

    Parameters
    ----------
    path : str or os.PathLike
        The file to create or replace (see :func:`atomic_path`).
    newline : str, optional
        Line ending written for each ``"\\n"`` (passed to :func:`open`); default ``"\\n"``.

    Yields
    ------
    file object
        A UTF-8 text file open for writing.
    """
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", newline=newline) as handle:
            yield handle
