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
  ``-`` is standard output for the outputs a command allows it for (text, not pictures).
- An output that is a symlink to a file (or a dangling symlink) is written through to its
  target, as shell redirection does; the link stays.
- A set writes its streams first and renames its files last, so that a stream that fails
  (``/dev/full``, a closed standard output) leaves every file as it was. What a command
  prints for its user (its summary, :meth:`OutputSet.print`) is such a stream too: written
  and flushed after the streams and before any rename, so a full standard output
  (``> /dev/full``) replaces no file either. Each rename is made
  in the folder the set checked (by its file descriptor, where the system allows it) and
  only if the file there is still none of the command's inputs (device and inode), so that
  a folder swapped for a link to the inputs' folder during the run replaces nothing.
- A picture output (``--plot``, ``--map``) must end in an extension matplotlib can write
  (``.png``, ``.jpg``, ``.pdf``, ``.svg``, ...): :func:`picture_format` names the format.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import errno
import os
import shutil
import stat
import sys
import tempfile
from pathlib import Path
from typing import IO, Iterable, Iterator

from ..errors import InputError

__all__ = ["atomic_write", "atomic_path", "check_output_path", "check_output_paths", "OutputSet", "STDOUT",
           "PICTURE_OPTIONS", "WRITE_FAILURES", "picture_format", "file_identity"]

#: The output path that means standard output (for the outputs that allow it).
STDOUT = "-"
#: The errors of a write that found no room (a full disk or quota, a file too large,
#: /dev/full) or a device that failed: the user's to fix (exit status 2), not internal errors.
WRITE_FAILURES = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO})
#: The options that name a picture: their path's extension must be a format matplotlib writes.
PICTURE_OPTIONS = ("--plot", "--map")
_TEMP_PREFIX, _TEMP_SUFFIX = ".po-", ".tmp"
# rename within a folder held open since the check (renameat): a folder path swapped during
# the run cannot redirect the rename
_DIR_FD = os.rename in os.supports_dir_fd and hasattr(os, "O_DIRECTORY")  # renameat, as os.replace uses
#: The picture formats matplotlib's Agg, PDF, PS and SVG back ends write, by extension
#: (matplotlib.backend_bases.FigureCanvasBase.get_supported_filetypes(), without importing
#: matplotlib before the work; JPEG, TIFF and WebP through Pillow, a matplotlib dependency).
_PICTURE_FORMATS = {"png": "png", "jpg": "jpeg", "jpeg": "jpeg", "pdf": "pdf", "svg": "svg", "svgz": "svgz",
                    "eps": "eps", "ps": "ps", "tif": "tiff", "tiff": "tiff", "webp": "webp"}


def picture_format(path: str | os.PathLike) -> str:
    """The matplotlib format a picture path names by its extension (``"png"`` without one).

    Parameters
    ----------
    path : str or os.PathLike
        The picture's file name, e.g. ``plan.jpg``.

    Returns
    -------
    str
        The ``format=`` to give ``Figure.savefig``: ``"png"``, ``"jpeg"``, ``"pdf"``,
        ``"svg"``, ...; ``"png"`` for a name without an extension (``/dev/null``, ``plot``).

    Raises
    ------
    InputError
        The extension is not one matplotlib writes.
    """
    suffix = Path(os.fspath(path)).suffix
    if not suffix:
        return "png"
    found = _PICTURE_FORMATS.get(suffix[1:].lower())
    if found is None:
        names = ", ".join(f".{ext}" for ext in _PICTURE_FORMATS)
        raise InputError(f"{os.fspath(path)}: a picture cannot be written as '{suffix}'; end its name in one of "
                         f"{names}")
    return found


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@dataclasses.dataclass(frozen=True)
class _Target:
    """A checked output: where it goes and how it is delivered."""

    path: Path  # as the user wrote it (for messages)
    label: str
    stream: bool = False  # an existing character device or FIFO: copied into, never replaced
    stdout: bool = False  # '-'
    real: Path | None = None  # where a file is written: the path with its symlinks resolved

    @property
    def file(self) -> Path:
        """The file written (a symlink's target; the path itself for a stream)."""
        return self.real if self.real is not None else self.path

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
        if sys.stdout is None:  # started with standard output closed (>&-)
            raise InputError(f"{label} -: standard output is closed; give the path of a file to write")
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
    # a symlink (dangling or not) is written through to its target, as '>' does; the link stays
    real = Path(os.path.realpath(target)) if os.path.islink(target) else target
    if real != target and os.path.isdir(real):
        raise InputError(f"{shown}: is a link to the folder {real}; give the path of a file to write")
    directory = real.parent if str(real.parent) else Path(".")
    if not directory.is_dir():
        what = "is a file, not a folder" if directory.exists() else "does not exist"
        raise InputError(f"{shown}: {directory} {what}; create the folder or choose another path")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise InputError(f"{shown}: cannot write in {directory} (permission denied); choose another path")
    size, limit = len(os.fsencode(real.name)), _name_max(directory)
    if size > limit:
        raise InputError(f"{shown}: the file name is {size} bytes, longer than the {limit} bytes a name may "
                         "have there; choose a shorter name")
    return _Target(target, label, real=real)


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


def file_identity(path: str | os.PathLike) -> tuple:
    """What makes two paths the same file, however they are spelt (the key :class:`OutputSet`
    compares outputs with inputs by).

    Parameters
    ----------
    path : str or os.PathLike
        A file; a symlink stands for its target.

    Returns
    -------
    tuple
        ``("inode", device, inode)`` of an existing file (a hard link or a symlink to it gives
        the same), else ``("path", resolved path)``.
    """
    return _identity(path)


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
    reusable : bool, optional
        Keep the output folders open after a ``with`` block ends, so that the set can be
        entered again and write its outputs anew in the same folders (a batch's summary,
        rewritten after every route); :meth:`close` releases them. Default False: the
        folders are closed when the block ends.

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

    def __init__(self, outputs: Iterable[tuple], inputs: Iterable[str | os.PathLike | None] = (), *,
                 reusable: bool = False) -> None:
        self._targets: dict[str, _Target] = {}
        self._pending: list[tuple[_Target, Path]] = []
        self._texts: list[tuple[str, IO[str] | None]] = []
        self._reusable = reusable
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
        for target in self._targets.values():  # after the checks above, which say more
            if target.label in PICTURE_OPTIONS:
                try:
                    picture_format(target.path)
                except InputError as exc:
                    raise InputError(f"{target.label} {exc}") from None
        self._inputs = input_ids
        self._folders: dict[Path, int] = {}  # each output folder, held open from the check to the renames
        try:
            for target in self._targets.values():
                if not target.stream and _DIR_FD and target.file.parent not in self._folders:
                    self._folders[target.file.parent] = _open_folder(target)
        except BaseException:
            self._close_folders()
            raise

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

    def print(self, text: str, file: IO[str] | None = None) -> None:
        """Print ``text`` (and a line end) to ``file`` when the block ends without an error:
        after the streams, before any file is renamed into place, flushed, so that a stream
        that fails (a full standard output) leaves every file output as it was.

        Parameters
        ----------
        text : str
            What the command says to its user (its summary).
        file : text stream, optional
            Where (default: standard output, as :func:`print`); None at the end (standard
            output closed when the command started) is refused as a stream that fails is.

        Raises
        ------
        InputError
            When the block ends: the stream cannot take the text (a full disk, ``/dev/full``);
            no file output is then written. A closed pipe (``| head``) raises
            :class:`BrokenPipeError`, as :func:`print` does.
        """
        self._texts.append((text, file))

    def __enter__(self) -> "OutputSet":
        if _ACTIVE.get() is None:  # an inner set inside an active one defers to it
            self._token = _ACTIVE.set(self)
        return self

    def __exit__(self, exc_type, exc, tb) -> None:  # noqa: ANN001
        if self._token is not None:
            _ACTIVE.reset(self._token)
            self._token = None
        writing = self._pending[-1][0] if self._pending else None  # the output being written when it failed
        try:
            if exc_type is None:
                # the copies into streams first (standard output, a FIFO, /dev/full), then
                # what the command prints: a stream that fails leaves every file as it was;
                # then the renames, each atomic
                ordered = sorted(self._pending, key=lambda item: not item[0].stream)
                for target, tmp in ordered:
                    if target.stream:
                        _deliver(target, tmp)
                files = any(not target.stream for target, _ in ordered)
                for text, file in self._texts:
                    _say(text, file, files=files)
                for target, tmp in ordered:
                    if not target.stream:
                        _deliver(target, tmp, folder=self._folders.get(target.file.parent), inputs=self._inputs)
        finally:
            for _, tmp in self._pending:
                _remove(tmp)
            self._pending = []
            self._texts = []
            if not self._reusable:
                self._close_folders()
        if (isinstance(exc, OSError) and not isinstance(exc, BrokenPipeError) and exc.errno in WRITE_FAILURES
                and writing is not None):  # the disk filled up while an output was written
            raise InputError(f"{writing.describe()}: cannot write it ({exc.strerror or exc}); nothing was written, "
                             "free some space or choose another output") from None

    def close(self) -> None:
        """Release the output folders a ``reusable`` set holds open (nothing for another set,
        whose block closes them)."""
        self._close_folders()

    def _close_folders(self) -> None:
        for fd in self._folders.values():
            os.close(fd)
        self._folders = {}


def _say(text: str, file: IO[str] | None, *, files: bool) -> None:
    """Print ``text`` to ``file`` (standard output if None) and flush it; a full one is one
    line naming it (:meth:`OutputSet.print`), and saying that no file was written if
    ``files`` (the set has file outputs)."""
    stream = sys.stdout if file is None else file
    if stream is None:  # started with standard output (or error) closed: refused, not lost
        name = "standard output" if file is None or sys.stdout is None else "standard error"
        raise InputError(f"{name} is closed, and the command prints its summary there; no file output was "
                         f"written; run it with {name} open ('> /dev/null' discards it)")
    try:
        print(text, file=stream)
        stream.flush()
    except BrokenPipeError:  # the reader stopped early (| head): the command line's status 141
        raise
    except OSError as exc:
        if exc.errno not in WRITE_FAILURES:
            raise
        name = ("standard output" if stream is sys.stdout or stream is sys.__stdout__ else
                "standard error" if stream is sys.stderr or stream is sys.__stderr__ else
                str(getattr(stream, "name", "the output stream")))
        unwritten = "no file output was written, " if files else ""
        raise InputError(f"{name}: cannot write ({exc.strerror or exc}); {unwritten}free some space or send {name} "
                         "elsewhere") from None


def _key(path: str | os.PathLike) -> str:
    text = os.fspath(path)
    return text if text in ("", STDOUT) else os.path.abspath(text)


def _make_temp(target: _Target) -> Path:
    """A new empty temporary file for ``target``: beside it, or in the temporary folder for a
    stream (a device's folder, /dev, is no place for it)."""
    directory = None if target.stream else (target.file.parent if str(target.file.parent) else Path("."))
    try:
        fd, tmp = tempfile.mkstemp(prefix=_TEMP_PREFIX, suffix=_TEMP_SUFFIX, dir=directory)
    except OSError as exc:
        raise InputError(f"{target.describe()}: cannot write in {directory or tempfile.gettempdir()} "
                         f"({exc.strerror}); choose another path") from None
    try:
        os.close(fd)
        # mkstemp makes 0600: a file replaced keeps its permissions (as shell redirection
        # leaves them), a new one gets the usual ones
        try:
            mode = stat.S_IMODE(os.stat(target.file).st_mode) if not target.stream else None
        except OSError:
            mode = None
        os.chmod(tmp, 0o666 & ~_umask() if mode is None else mode)
    except BaseException:  # SIGTERM or Ctrl-C between the calls: no temporary file is left
        _remove(Path(tmp))
        raise
    return Path(tmp)


def _open_folder(target: _Target) -> int:
    """The folder of a file output, opened (a descriptor to rename in, see :func:`_deliver`)."""
    folder = target.file.parent if str(target.file.parent) else Path(".")
    try:
        return os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError as exc:
        raise InputError(f"{target.describe()}: cannot open its folder {folder} ({exc.strerror}); choose another "
                         "path") from None


def _deliver(target: _Target, tmp: Path, *, folder: int | None = None, inputs: dict | None = None) -> None:
    """Put the finished temporary file in place: rename, or copy into a stream.

    ``folder``: the descriptor of the output's folder as checked (the rename is made there, or
    fails if the temporary file is not there: the folder path was swapped during the run);
    ``inputs``: the command's inputs by identity, none of which the output may now be.
    """
    if not target.stream:
        now = _identity(target.file)
        if inputs and now in inputs:
            raise InputError(f"{target.describe()}: is now the input {inputs[now]} (the output's folder or file "
                             "was changed while the command ran); nothing was written, choose another output path")
        if folder is None:
            os.replace(tmp, target.file)
            return
        try:
            os.replace(tmp.name, target.file.name, src_dir_fd=folder, dst_dir_fd=folder)
        except FileNotFoundError:
            raise InputError(f"{target.describe()}: its folder {target.file.parent} was replaced while the command "
                             "ran; nothing was written, run again") from None
        return
    try:
        with open(tmp, "rb") as source:
            if target.stdout:
                sys.stdout.flush()
                shutil.copyfileobj(source, sys.stdout.buffer)
                sys.stdout.buffer.flush()
            else:
                with open(target.path, "wb") as sink:  # a device or FIFO: written into, not replaced
                    shutil.copyfileobj(source, sink)
    except BrokenPipeError:  # the reader stopped early (| head): the command line's status 141
        raise
    except OSError as exc:  # /dev/full, a device that refuses the write
        if exc.errno not in WRITE_FAILURES and not isinstance(exc, PermissionError):
            raise
        raise InputError(f"{target.describe()}: cannot write it ({exc.strerror or exc}); no file output was "
                         "written, choose another output") from None


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
    folder = _open_folder(target) if _DIR_FD and not target.stream else None
    try:
        tmp = _make_temp(target)
        try:
            yield tmp
            _deliver(target, tmp, folder=folder)
        finally:
            _remove(tmp)
    finally:
        if folder is not None:
            os.close(folder)


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
        A UTF-8 text file open for writing. Text that UTF-8 cannot encode (the lone
        surrogates Python keeps for the bytes of a file name that is not UTF-8) is written
        as its escape (``\\udcff``), never an error after the work is done.
    """
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8", errors="backslashreplace", newline=newline) as handle:
            yield handle

