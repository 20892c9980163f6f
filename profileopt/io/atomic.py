"""Atomic output files: a failed or interrupted run never leaves a half-written file.

One design for every output of the package:

- :func:`atomic_path` / :func:`atomic_write` write a temporary file (a short name,
  ``.po-XXXXXXXX.tmp``, so that a legal long output name never fails for its temporary
  name) beside the output and rename it onto the output when the block succeeds; a failure
  removes the temporary file and leaves an earlier output untouched.
- :class:`OutputSet` holds every output of one command. It checks them all before any work
  (empty path, missing or read-only folder, a folder, a name too long, an output that is one
  of the command's inputs, two outputs that are the same file), and while it is active the
  writers above only write their temporary files: the set renames them all at its end, so a
  command writes all its outputs or none.
- An output that exists and is not a regular file (a character device such as
  ``/dev/null`` or a terminal, a FIFO, a symlink to ``/proc/self/fd/1``) is never replaced:
  the finished temporary file is copied into it. A block device or a socket is refused.
  ``-`` is standard output for the outputs a command allows it for (text, not PNG).
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import os
import shutil
import stat
import sys
import tempfile
from pathlib import Path
from typing import IO, Iterable, Iterator

from ..errors import InputError

__all__ = ["atomic_write", "atomic_path", "check_output_path", "check_output_paths", "OutputSet", "STDOUT"]

#: The output path that means standard output (for the outputs that allow it).
STDOUT = "-"
_TEMP_PREFIX, _TEMP_SUFFIX = ".po-", ".tmp"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@dataclasses.dataclass(frozen=True)
class _Target:
    """A checked output: where it goes and how it is delivered."""

    path: Path
    label: str
    stream: bool = False  # an existing character device or FIFO: copied into, never replaced
    stdout: bool = False  # '-'

    def describe(self) -> str:
        return f"{self.label} {self.path}" if self.label else str(self.path)


def _name_max(directory: Path) -> int:
    try:
        return os.pathconf(directory, "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):
        return 255


def _inspect(path: str | os.PathLike, label: str = "", *, stdout_ok: bool = False) -> _Target:
    """Check one output path; returns how it is to be written (see :func:`check_output_path`)."""
    text = os.fspath(path)
    where = f"{label} " if label else ""
    if not text:
        raise InputError(f"{where}'': the output path is empty; give the path of a file to write")
    if text == STDOUT and label:  # '-' means standard output only on the command line
        if not stdout_ok:
            raise InputError(f"{label} -: this output cannot go to standard output; give the path of a file")
        return _Target(Path(STDOUT), label, stream=True, stdout=True)
    target = Path(text)
    shown = f"{where}{target}"
    try:
        st = os.stat(target)
    except (FileNotFoundError, NotADirectoryError):
        st = None
    except OSError as exc:  # name too long, symlink loop, permission denied on a folder
        raise InputError(f"{shown}: cannot write it ({exc.strerror}); choose another path") from None
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise InputError(f"{shown}: is a folder; give the path of a file to write")
        if stat.S_ISCHR(st.st_mode) or stat.S_ISFIFO(st.st_mode):
            if not os.access(target, os.W_OK):
                raise InputError(f"{shown}: cannot write it (permission denied); choose another path")
            return _Target(target, label, stream=True)
        if not stat.S_ISREG(st.st_mode):
            raise InputError(f"{shown}: exists and is neither a regular file, a character device nor a FIFO; "
                             "it is never replaced, choose another path")
    directory = target.parent if str(target.parent) else Path(".")
    if not directory.is_dir():
        what = "is a file, not a folder" if directory.exists() else "does not exist"
        raise InputError(f"{shown}: {directory} {what}; create the folder or choose another path")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise InputError(f"{shown}: cannot write in {directory} (permission denied); choose another path")
    size, limit = len(os.fsencode(target.name)), _name_max(directory)
    if size > limit:
        raise InputError(f"{shown}: the file name is {size} bytes, longer than the {limit} bytes a name may "
                         "have there; choose a shorter name")
    return _Target(target, label)


def check_output_path(path: str | os.PathLike) -> Path:
    """Refuse, before any work is done, an output path that cannot be written.

    Commands check every output first (:class:`OutputSet`), so that a run that would fail at
    its second output never writes its first one.

    Parameters
    ----------
    path : str or os.PathLike
        The file to be written: not empty, its folder must exist and be writable, its name
        not longer than the folder allows, and it must not be a folder. An existing
        character device or FIFO is accepted (it is written into, never replaced); any
        other file that is not a regular file is refused.

    Returns
    -------
    pathlib.Path
        ``path`` as a :class:`~pathlib.Path`.

    Raises
    ------
    InputError
        The path is empty, its folder does not exist or is not writable, the path is a
        folder, a block device or a socket, or its name is too long.
    """
    return _inspect(path).path


def check_output_paths(*paths: str | os.PathLike | None) -> None:
    """:func:`check_output_path` for every path given (``None``: that output is not wanted).

    Parameters
    ----------
    *paths : str or os.PathLike or None
        The output paths to check; None is skipped (an empty string is refused).

    Raises
    ------
    InputError
        At the first path that cannot be written.
    """
    for path in paths:
        if path is not None:
            check_output_path(path)


def _identity(path: str | os.PathLike) -> tuple:
    """What makes two paths the same file: device and inode if it exists, else the resolved path."""
    try:
        st = os.stat(path)
    except OSError:
        return ("path", os.path.realpath(path))
    return ("inode", st.st_dev, st.st_ino)


_ACTIVE: contextvars.ContextVar["OutputSet | None"] = contextvars.ContextVar("profileopt_output_set", default=None)


class OutputSet:
    """Every output of one command: checked together before any work, written all or none.

    Construct it before the work (it checks every output and raises at the first bad one),
    then write the outputs inside ``with output_set:``: every :func:`atomic_path` /
    :func:`atomic_write` of one of its paths writes only its temporary file, and the set
    renames them all when the block ends without an exception (and removes them all when
    it raises, an interrupt and SIGTERM through the command line included).

    Parameters
    ----------
    outputs : iterable of (str, path or None) or (str, path or None, bool)
        ``(label, path)`` or ``(label, path, stdout_ok)``: the option that names the output
        (``"-o"``, for messages), its path (None: not wanted), and whether ``-`` may mean
        standard output for it (text outputs; default False).
    inputs : iterable of path or None, optional
        The files the command reads: an output that is one of them (the same file however
        it is spelt, a hard link or symlink included) is refused.

    Raises
    ------
    InputError
        A bad output (see :func:`check_output_path`), one that is an input, or two outputs
        that are the same file.

    Examples
    --------
    >>> outputs = OutputSet([("-o", "out.csv", True), ("--plot", None)], inputs=["route.csv"])
    >>> with outputs:  # doctest: +SKIP
    ...     write_profile(profile, "out.csv")
    """

    def __init__(self, outputs: Iterable[tuple], inputs: Iterable[str | os.PathLike | None] = ()) -> None:
        self._targets: dict[str, _Target] = {}
        self._pending: list[tuple[_Target, Path]] = []
        self._token: contextvars.Token | None = None
        seen: dict[tuple, _Target] = {}
        input_ids = {}
        for path in inputs:
            if path is not None and os.fspath(path) not in ("", STDOUT):
                input_ids.setdefault(_identity(path), os.fspath(path))
        for label, path, *rest in outputs:
            if path is None:
                continue
            target = _inspect(path, label, stdout_ok=bool(rest and rest[0]))
            if not target.stdout:
                identity = _identity(target.path)
                if identity in input_ids:
                    raise InputError(f"{target.describe()}: is the input {input_ids[identity]}; writing it would "
                                     "replace the input, choose another output path")
                key = identity
            else:
                key = ("stdout",)
            if key in seen:
                raise InputError(f"{target.describe()}: is also the output of {seen[key].describe()}; give each "
                                 "output its own path")
            seen[key] = target
            self._targets[_key(path)] = target

    @property
    def paths(self) -> list[Path]:
        """The outputs, in the order given (``-`` for standard output)."""
        return [t.path for t in self._targets.values()]

    @property
    def uses_stdout(self) -> bool:
        """True if one of the outputs is standard output (print messages to stderr then)."""
        return any(t.stdout for t in self._targets.values())

    def _target(self, path: str | os.PathLike) -> _Target | None:
        return self._targets.get(_key(path))

    def __enter__(self) -> "OutputSet":
        if _ACTIVE.get() is None:  # an inner set inside an active one defers to it
            self._token = _ACTIVE.set(self)
        return self

    def __exit__(self, exc_type, exc, tb) -> None:  # noqa: ANN001
        if self._token is not None:
            _ACTIVE.reset(self._token)
            self._token = None
        try:
            if exc_type is None:
                # renames first: each is atomic and cannot be half done; then the copies into
                # streams (standard output, a FIFO, /dev/null), which a reader may stop early
                for target, tmp in sorted(self._pending, key=lambda item: item[0].stream):
                    _deliver(target, tmp)
        finally:
            for _, tmp in self._pending:
                _remove(tmp)
            self._pending = []


def _key(path: str | os.PathLike) -> str:
    text = os.fspath(path)
    return text if text in ("", STDOUT) else os.path.abspath(text)


def _make_temp(target: _Target) -> Path:
    """A new empty temporary file for ``target``: beside it, or in the temporary folder for a
    stream (a device's folder, /dev, is no place for it)."""
    directory = None if target.stream else (target.path.parent if str(target.path.parent) else Path("."))
    try:
        fd, tmp = tempfile.mkstemp(prefix=_TEMP_PREFIX, suffix=_TEMP_SUFFIX, dir=directory)
    except OSError as exc:
        raise InputError(f"{target.describe()}: cannot write in {directory or tempfile.gettempdir()} "
                         f"({exc.strerror}); choose another path") from None
    os.close(fd)
    os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; outputs get the usual permissions
    return Path(tmp)


def _deliver(target: _Target, tmp: Path) -> None:
    """Put the finished temporary file in place: rename, or copy into a stream."""
    if not target.stream:
        os.replace(tmp, target.path)
        return
    with open(tmp, "rb") as source:
        if target.stdout:
            sys.stdout.flush()
            shutil.copyfileobj(source, sys.stdout.buffer)
            sys.stdout.buffer.flush()
        else:
            with open(target.path, "wb") as sink:  # a device or FIFO: written into, not replaced
                shutil.copyfileobj(source, sink)


def _remove(tmp: Path) -> None:
    with contextlib.suppress(FileNotFoundError):
        tmp.unlink()


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path for ``path``; on success it becomes ``path``.

    If the block raises, the temporary file is removed and ``path`` (and any good earlier
    file there) is left untouched. Inside an active :class:`OutputSet` that holds ``path``,
    the temporary file is put in place when the set ends, together with the set's other
    outputs. Use it for writers that want a file name (matplotlib's ``savefig``, C code
    generators); :func:`atomic_write` for text.

    Parameters
    ----------
    path : str or os.PathLike
        The file to create or replace; checked first with :func:`check_output_path`. An
        existing character device or FIFO is written into, never replaced.

    Yields
    ------
    pathlib.Path
        A temporary file (``.po-XXXXXXXX.tmp``, in the folder of ``path``), to be written
        by the block.

    Raises
    ------
    InputError
        ``path`` cannot be written, or no temporary file can be made in its folder.
    """
    active = _ACTIVE.get()
    target = active._target(path) if active is not None else None
    if target is not None:
        tmp = _make_temp(target)
        active._pending.append((target, tmp))  # the set puts it in place or removes it
        yield tmp
        return
    target = _inspect(path)
    tmp = _make_temp(target)
    try:
        yield tmp
        _deliver(target, tmp)
    finally:
        _remove(tmp)


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

