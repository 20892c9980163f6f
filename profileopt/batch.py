"""Many routes at once: ``profileopt batch`` and :func:`plan_many`.

A batch is a list of :class:`BatchRow` (from a manifest, :func:`read_manifest`): each row is
one ``profileopt plan`` run, its route and its options (the plan command's long options
without the dashes). Each route is planned exactly as ``profileopt plan ROUTE -o ID.csv
OPTIONS`` plans it (the same code, :func:`profileopt.cli.plan.execute`), so the profiles
are the same bytes. The rows run on Dask's distributed scheduler: a local cluster of worker
processes (one thread each) by default, or any cluster given by its scheduler's address or
a :class:`dask.distributed.Client`; ``workers=1`` without a scheduler plans one route
after another in this process, without Dask.

What a batch writes, into its output folder:

- ``ID.csv`` for each row planned (written atomically, as ``plan -o`` writes);
- ``summary.csv``, one row per manifest row: :data:`SUMMARY_COLUMNS` (``status`` is ``ok``
  or ``failed``, ``error`` the one-line error of a row that failed), rewritten atomically
  after every route, so a batch stopped at any point (a crash, SIGTERM, Ctrl-C) leaves a
  summary of what was done.

With pyarrow installed (the ``parquet`` extra), ``summary.parquet`` holds the same table
with typed columns, written with the last ``summary.csv`` when the batch ends (also when it
is stopped by SIGTERM or Ctrl-C; after a crash of the process itself, by the next run): a
Parquet file per route cost the batch's own process 0.02 s a route, beside the workers.

A row that fails does not stop the others. Run again, a batch plans only the rows whose
profile is missing, or failed, or whose inputs changed: ``input_sha256`` hashes the
profileopt version, the row's options, the bytes of its route and vehicle files, and the
names, sizes and modification times of its terrain files.
"""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import io
import json
import math
import os
import re
from pathlib import Path
from typing import Any, Iterable, Sequence

from .core.vehicle import names_vehicle_file
from .errors import InputError
from .progress import NO_PROGRESS, Progress

__all__ = ["BatchRow", "read_manifest", "plan_many", "SUMMARY_COLUMNS", "SUMMARY_FILE", "SUMMARY_PARQUET",
           "MISSING_DASK"]

#: The summary's file name in the output folder.
SUMMARY_FILE = "summary.csv"
#: The summary as Parquet, beside the CSV when pyarrow (the ``parquet`` extra) is installed.
SUMMARY_PARQUET = "summary.parquet"
#: The summary's columns, in order.
SUMMARY_COLUMNS = ("id", "status", "travel_time_s", "distance_m", "mean_speed_mps", "segments", "force_ratio",
                   "binding", "notes", "error", "route", "profile", "input_sha256")
#: What to install for more than one worker.
MISSING_DASK = "planning on several workers needs Dask: pip install 'profileopt[batch]' (or give --workers 1)"
#: Options a batch sets itself, or that write files it does not collect.
_NOT_IN_A_ROW = {"output", "plot", "map", "json", "quiet", "help"}
_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,99}")


@dataclasses.dataclass(frozen=True)
class BatchRow:
    """One route of a batch.

    Attributes
    ----------
    id : str
        The row's name: its profile is ``ID.csv`` (letters, digits, ``.``, ``_``, ``-``).
    route : str
        The route file or track (as ``profileopt plan`` takes it).
    options : tuple of (str, str)
        ``profileopt plan``'s long options without the dashes and their values as text
        (``("segment_length", "2")``, ``("vehicle", "atv-resonant")``); a switch's value
        is ``"true"`` or ``"false"`` (``refine``, ``no_refine``).
    """

    id: str
    route: str
    options: tuple[tuple[str, str], ...] = ()

    def argv(self, output: str | os.PathLike) -> list[str]:
        """The ``profileopt plan`` arguments of this row, writing the profile to ``output``.

        Parameters
        ----------
        output : str or os.PathLike
            The profile CSV to write (``-o``).

        Returns
        -------
        list of str
            The route, ``-o OUTPUT --quiet``, then each option as ``--name=value`` (a
            switch as ``--name`` or ``--no-name``).
        """
        argv = [self.route, "-o", os.fspath(output), "--quiet"]
        for name, value in self.options:
            flag = "--" + name.replace("_", "-")
            if name == "terrain":
                argv.extend(f"{flag}={part}" for part in value.split(";"))
            elif value.lower() in ("true", "yes"):
                argv.append(flag)
            elif value.lower() in ("false", "no"):
                argv.append("--no-" + name.replace("_", "-"))
            else:
                argv.append(f"{flag}={value}")
        return argv


def read_manifest(path: str | os.PathLike) -> list[BatchRow]:
    """Read a batch manifest: CSV (a header, one row per route) or JSON (a list of objects).

    Columns: ``id`` and ``route``, then optionally ``terrain``, ``vehicle``, ``model`` and
    any long option of ``profileopt plan`` without its dashes (``segment_length``,
    ``roughness_class``, ``v0``, ``refine`` = true/false, ...); an empty cell leaves the
    option at its default. ``terrain`` is a terrain file, a folder of tiles, or several
    of them separated by ``;`` (in JSON, also a list). Relative paths (``route``,
    ``terrain``, a ``vehicle`` that is a file) are relative to the manifest's folder.

    Parameters
    ----------
    path : str or os.PathLike
        The manifest (``.csv`` or ``.json``).

    Returns
    -------
    list of BatchRow

    Raises
    ------
    InputError
        The file cannot be read; a column that is no option of ``plan`` (named, with the
        nearest); a missing or repeated ``id``, or one that is no file name; a missing
        ``route``.
    """
    from .io.table import read_text

    path = Path(path)
    text = read_text(path, "manifest", line_ends=path.suffix.lower() != ".json")
    if path.suffix.lower() == ".json":
        try:
            records = json.loads(text)
        except (ValueError, RecursionError) as exc:
            raise InputError(f"{path}: not a JSON manifest ({str(exc)[:80]}); give a list of objects, one per "
                             'route, e.g. [{"id": "a", "route": "a.csv"}]') from None
        if not isinstance(records, list) or not all(isinstance(r, dict) for r in records):
            raise InputError(f"{path}: a JSON manifest is a list of objects, one per route, e.g. "
                             '[{"id": "a", "route": "a.csv"}]')
        rows = [(f"item {k + 1}", {str(key): "" if value is None else _text(value) for key, value in r.items()})
                for k, r in enumerate(records)]
    else:
        reader = csv.DictReader(io.StringIO(text))
        if reader.fieldnames is None:
            raise InputError(f"{path}: the manifest is empty; give a header (id,route,...) and one row per route")
        rows = []
        for k, record in enumerate(reader):
            if None in record:
                raise InputError(f"{path}: line {reader.line_num}: more cells than the header has columns")
            rows.append((f"line {reader.line_num}", {key.strip(): (value or "").strip()
                                                      for key, value in record.items()}))
    options = _plan_options()
    out: list[BatchRow] = []
    seen: dict[str, str] = {}
    for where, record in rows:
        for key in record:
            if key not in ("id", "route") and key not in options:
                import difflib

                near = difflib.get_close_matches(key, [*options, "id", "route"], n=1)
                hint = f"; did you mean '{near[0]}'?" if near else ""
                raise InputError(f"{path}: {where}: column '{key}' is no option of profileopt plan (its long "
                                 f"options without the dashes, e.g. segment_length){hint}")
        ident, route = record.get("id", ""), record.get("route", "")
        if not _ID.fullmatch(ident) or ident.lower() in ("summary",):
            raise InputError(f"{path}: {where}: id '{ident}' must be a file name of letters, digits, '.', '_' and "
                             "'-' (not 'summary'), starting with a letter or digit")
        if ident in seen:
            raise InputError(f"{path}: {where}: id '{ident}' is also the id of {seen[ident]}; give each row its own")
        seen[ident] = where
        if not route:
            raise InputError(f"{path}: {where}: no route; give the route file in the column 'route'")
        pairs = []
        for key, value in record.items():
            if key in ("id", "route") or value == "":
                continue
            if key == "terrain":  # a file, a folder of tiles, or several of them separated by ';'
                value = ";".join(_beside(path, part.strip()) for part in value.split(";") if part.strip())
            elif key == "vehicle" and names_vehicle_file(value):  # a file, not a bundled name
                value = _beside(path, value)
            pairs.append((key, value))
        out.append(BatchRow(ident, _beside(path, route), tuple(pairs)))
    if not out:
        raise InputError(f"{path}: the manifest has no rows; give one row per route")
    return out


def plan_many(rows: Sequence[BatchRow], out_dir: str | os.PathLike, *, workers: int | None = None,
              scheduler: str | None = None, client: Any = None, progress: Progress = NO_PROGRESS,
              inputs: Iterable[str | os.PathLike] = ()) -> list[dict[str, Any]]:
    """Plan every row, each as ``profileopt plan`` would, into ``out_dir``.

    No output may replace a file the batch reads: before any work, a ``summary.csv`` or
    ``summary.parquet`` that is one of them (the same file however it is spelt, a symlink or
    hard link included), or a row's ``ID.csv`` that is the manifest or another row's route,
    vehicle or terrain file, is refused (a row's ``ID.csv`` that is its own route fails that
    row, as ``profileopt plan`` refuses it). Every row's profile and the summary are checked
    again when they are put in place (device and inode), and the summary is written in the
    folder checked at the start (held open), so an output folder swapped for a link while the
    batch runs replaces nothing.

    Parameters
    ----------
    rows : sequence of BatchRow
        The routes (:func:`read_manifest`).
    out_dir : str or os.PathLike
        The output folder (created if missing): ``ID.csv`` per row and ``summary.csv``.
    workers : int, optional
        Worker processes of the local cluster (default: the machine's cores). ``1`` without
        ``scheduler`` or ``client``: one route after another in this process, without Dask.
    scheduler : str, optional
        The address of a running Dask scheduler (``tcp://HOST:PORT``) to plan on.
    client : dask.distributed.Client, optional
        A client of a running cluster to plan on (instead of ``scheduler``).
    progress : Progress, optional
        Told of each route done (:mod:`profileopt.progress`).
    inputs : iterable of path, optional
        More files the batch reads that no output may replace, besides each row's route,
        vehicle and terrain files: its manifest (``profileopt batch --manifest``).

    Returns
    -------
    list of dict
        The summary's rows (:data:`SUMMARY_COLUMNS`), in the order of ``rows``; the same as
        ``summary.csv``.

    Raises
    ------
    InputError
        The output folder cannot be made, Dask is missing for several workers
        (:data:`MISSING_DASK`), ``workers`` is not a whole number >= 1, an output would
        replace an input (naming both), or the output folder was replaced while the batch ran.
    """
    from .io.atomic import OutputSet

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(f"{out}: exists and is not a folder; give the batch's output folder")
    if workers is not None and not (isinstance(workers, int) and workers >= 1):
        raise InputError(f"workers = {workers!r} must be a whole number >= 1")
    read = [(os.fspath(path), "the manifest", None) for path in inputs]
    for row in rows:
        read += [(path, what, row.id) for path, what in _row_inputs(row)]
    _check_outputs(rows, out, read)  # before any work: nothing the batch reads is one of its outputs
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"{out}: cannot create the output folder ({exc.strerror}); choose another path") from None
    protected = list(dict.fromkeys(path for path, _, _ in read))  # no output may be one of them, at its rename too
    summary_files = [out / SUMMARY_FILE, *([out / SUMMARY_PARQUET] if _has_pyarrow() else [])]
    # the summary's folder held open from now to the last rewrite (renamed there, by descriptor)
    summary_set = OutputSet([("summary", path) for path in summary_files], inputs=protected, reusable=True)
    try:
        return _plan_rows(rows, out, workers, scheduler, client, progress, protected, summary_set)
    finally:
        summary_set.close()


def _plan_rows(rows: Sequence[BatchRow], out: Path, workers: int | None, scheduler: str | None, client: Any,
               progress: Progress, protected: list[str], summary_set: Any) -> list[dict[str, Any]]:
    """:func:`plan_many`'s work, once its outputs are checked."""
    earlier = _read_summary(out / SUMMARY_FILE)
    done: dict[str, dict[str, Any]] = {}
    todo: list[tuple[BatchRow, str]] = []
    for row in rows:
        digest = _input_sha256(row)
        before = earlier.get(row.id)
        if (before is not None and before.get("status") == "ok" and before.get("input_sha256") == digest
                and (out / f"{row.id}.csv").is_file()):
            done[row.id] = before  # planned before with the same inputs and options: kept
        else:
            todo.append((row, digest))
    progress.expect(len(todo))

    planned: list[str] = []  # the rows planned in this run

    def write_summary(*, parquet: bool) -> None:
        _write_summary(out / SUMMARY_FILE, [done[r.id] for r in rows if r.id in done], summary_set, parquet=parquet)

    def finished(row: BatchRow, digest: str, result: dict[str, Any]) -> None:
        done[row.id] = {"id": row.id, **result, "route": row.route,
                        "profile": f"{row.id}.csv" if result["status"] == "ok" else "", "input_sha256": digest}
        planned.append(row.id)
        progress.step(f"{row.id}: {done[row.id]['status']}")
        write_summary(parquet=False)

    try:
        _plan_todo(todo, out, workers, scheduler, client, protected, finished)
    finally:  # the end, or SIGTERM / Ctrl-C: the CSV again and the Parquet table beside it (also
        # when an earlier batch was killed between its last CSV and its Parquet table)
        if _has_pyarrow() and (planned or _parquet_behind(out)):
            write_summary(parquet=True)
    return [done[row.id] for row in rows]


def _parquet_behind(out: Path) -> bool:
    """Whether ``summary.parquet`` is missing or older than ``summary.csv`` in ``out``."""
    try:
        csv_ns = (out / SUMMARY_FILE).stat().st_mtime_ns
    except OSError:
        return False
    try:
        return (out / SUMMARY_PARQUET).stat().st_mtime_ns < csv_ns
    except OSError:
        return True


def _plan_todo(todo: list[tuple[BatchRow, str]], out: Path, workers: int | None, scheduler: str | None,
               client: Any, protected: list[str], finished: Any) -> None:
    """Plan the rows not yet done, in this process or on Dask, telling ``finished`` of each."""
    if todo and workers == 1 and scheduler is None and client is None:
        for row, digest in todo:
            finished(row, digest, plan_row(row.argv(out / f"{row.id}.csv"), protected))
    elif todo:
        try:
            from dask.distributed import Client, LocalCluster, as_completed
        except ImportError:
            raise InputError(MISSING_DASK) from None
        owned = []
        try:
            if client is None:
                if scheduler is not None:
                    client = Client(scheduler, timeout="10s")
                else:
                    import dask

                    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # the workers inherit it
                    with dask.config.set(_QUIET_CLUSTER):
                        cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                                               processes=True, dashboard_address=None)
                    owned.append(cluster)
                    client = Client(cluster)
                owned.insert(0, client)
            # the largest routes first, so that no worker is left with a long one at the end
            largest_first = sorted(todo, key=lambda item: -_route_bytes(item[0]))
            futures = {client.submit(plan_row, row.argv(out / f"{row.id}.csv"), protected,
                                     key=f"profileopt-plan-{row.id}-{digest[:12]}", pure=False): (row, digest)
                       for row, digest in largest_first}
            for future in as_completed(futures):
                row, digest = futures[future]
                try:
                    result = future.result()
                except Exception as exc:  # the worker died (out of memory, killed): this row only
                    result = _failed(f"the worker planning it stopped ({type(exc).__name__}: {exc})")
                finished(row, digest, result)
        except OSError as exc:  # no scheduler at that address
            raise InputError(f"cannot reach the Dask scheduler {scheduler} ({exc}); start one ('dask scheduler') "
                             "or leave --scheduler out for a local cluster") from None
        finally:
            for thing in owned:
                thing.close()


#: Dask settings of the batch's own local cluster, which has no dashboard to feed. Measured on
#: 40 routes of 3 km, 2 workers on 2 cores: the workers' statistical profiler (every task's stack
#: sampled each 10 ms) made the plans about 3 % slower; the event-loop tick (every 20 ms in the
#: command's process and in each worker, only to warn of a blocked loop) and the system monitor
#: (CPU, memory, disk and network every 0.5 s, for the dashboard) took 0.56 s of the command's
#: CPU during the plans, 0.31 s at these intervals, and the batch 0.2-0.4 s less time.
_QUIET_CLUSTER = {"distributed.worker.profile.enabled": False, "distributed.admin.tick.interval": "1s",
                  "distributed.admin.system-monitor.interval": "2s"}


def plan_row(argv: Sequence[str], inputs: Iterable[str | os.PathLike] = ()) -> dict[str, Any]:
    """Plan one route as ``profileopt plan ARGV`` does; the summary row of its outcome.

    Parameters
    ----------
    argv : sequence of str
        ``profileopt plan``'s arguments (:meth:`BatchRow.argv`).
    inputs : iterable of path, optional
        More files the profile may not replace (the batch's manifest and every row's inputs),
        checked before the plan and again when the profile is put in place.

    Returns
    -------
    dict
        ``status`` ``"ok"`` with the travel time, distance, mean speed, segments, force
        ratio, binding shares and notes; or ``"failed"`` with ``error``, one line.
    """
    from .cli import plan as command
    from .cli.app import WORKER_MMAP_THRESHOLD_BYTES, keep_arrays_on_the_heap
    from .cli.messages import flags_for_parameters
    from .errors import PlanningError

    keep_arrays_on_the_heap(WORKER_MMAP_THRESHOLD_BYTES)  # Dask's workers are started with MALLOC_TRIM_THRESHOLD_=65536
    parser = _plan_parser()
    try:
        args = parser.parse_args(list(argv))
    except _ArgumentError as exc:
        return _failed(str(exc))
    try:
        summary, _ = command.execute(args, inputs=list(inputs))
    except InputError as exc:  # bad input, or infeasible: the one line `plan` says
        return _failed(flags_for_parameters(str(exc)))
    except PlanningError as exc:
        return _failed(f"the planner stopped: {exc}")
    force = summary["margins"]["force"]["ratio"]
    return {"status": "ok", "travel_time_s": summary["travel_time_s"], "distance_m": summary["distance_m"],
            "mean_speed_mps": summary["mean_speed_mps"], "segments": summary["segments"],
            "force_ratio": force, "binding": json.dumps(summary["binding"], separators=(",", ":")),
            "notes": " | ".join(summary["notes"]), "error": ""}


def _route_bytes(row: BatchRow) -> int:
    """The size of a row's route file (bytes; 0 if it cannot be read): how long its plan takes,
    roughly, to hand the longest routes out first."""
    try:
        return os.path.getsize(row.route)
    except OSError:
        return 0


def _failed(error: str) -> dict[str, Any]:
    return {"status": "failed", "travel_time_s": None, "distance_m": None, "mean_speed_mps": None,
            "segments": None, "force_ratio": None, "binding": "", "notes": "", "error": error}


class _ArgumentError(Exception):
    """A row's option argparse refuses (its message, instead of exiting)."""


def _plan_parser():  # noqa: ANN202  (argparse.ArgumentParser)
    import argparse

    from .cli import plan as command

    class Parser(argparse.ArgumentParser):
        def error(self, message: str):  # noqa: ANN202
            raise _ArgumentError(f"profileopt plan: {message}")

    parser = Parser(prog="profileopt plan", add_help=False)
    command.arguments(parser)
    return parser


def _plan_options() -> set[str]:
    """``profileopt plan``'s long options without the dashes, as manifest columns (those a
    batch sets itself left out)."""
    names = set()
    for action in _plan_parser()._actions:
        for option in action.option_strings:
            if option.startswith("--"):
                names.add(option[2:].replace("-", "_"))
    return names - _NOT_IN_A_ROW


def _beside(manifest: Path, value: str) -> str:
    """A path of a manifest's cell: relative ones relative to the manifest's folder."""
    return value if os.path.isabs(value) else str(manifest.parent / value)


def _text(value: Any) -> str:
    if isinstance(value, list):  # a JSON list of terrain tiles
        return ";".join(_text(item) for item in value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and math.isfinite(value):
        return repr(value)
    return str(value)


def _input_sha256(row: BatchRow) -> str:
    """What a row's profile depends on: the version, its options, the bytes of its route and
    vehicle files, and its terrain files' names, sizes and modification times (tiles can be
    gigabytes, read again for every route if hashed)."""
    from . import __version__
    from .io.tiles import terrain_files

    digest = hashlib.sha256(f"profileopt {__version__}\n{row.id}\n{row.route}\n".encode())
    digest.update(json.dumps(row.options).encode())
    for name in (row.route, *(value for key, value in row.options if key == "vehicle")):
        if os.path.isfile(name):
            with open(name, "rb") as handle:
                for block in iter(lambda: handle.read(1 << 20), b""):
                    digest.update(block)
    terrain = [value for key, value in row.options if key == "terrain"]
    if terrain:
        try:
            files = terrain_files(terrain[0].split(";"))
        except InputError:
            files = []  # the plan will say what is wrong
        for file in files:
            try:
                stat = os.stat(file)
            except OSError:
                continue
            digest.update(f"{os.path.realpath(file)}\n{stat.st_size}\n{stat.st_mtime_ns}\n".encode())
    return digest.hexdigest()


def _read_summary(path: Path) -> dict[str, dict[str, Any]]:
    if not path.is_file():
        return {}
    try:
        with open(path, newline="", encoding="utf-8") as handle:
            return {row["id"]: _typed(row) for row in csv.DictReader(handle) if row.get("id")}
    except (OSError, UnicodeDecodeError, csv.Error, KeyError, ValueError):
        return {}  # unreadable: everything is planned again


def _typed(row: dict[str, str]) -> dict[str, Any]:
    """A summary row read back, its numbers as numbers (as :func:`plan_row` gives them)."""
    out: dict[str, Any] = dict(row)
    for key in ("travel_time_s", "distance_m", "mean_speed_mps", "force_ratio"):
        out[key] = float(row[key]) if row.get(key) else None
    out["segments"] = int(row["segments"]) if row.get("segments") else None
    return out


def _write_summary(path: Path, rows: Iterable[dict[str, Any]], outputs: Any, *, parquet: bool) -> None:
    """``summary.csv`` (and, with ``parquet``, ``summary.parquet``), written together by
    ``outputs``, the batch's :class:`~profileopt.io.atomic.OutputSet` of them: renamed into
    the folder checked at the start, and only if neither is now one of the batch's inputs."""
    from .io.atomic import atomic_write

    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=SUMMARY_COLUMNS, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({key: "" if row.get(key) is None else row.get(key) for key in SUMMARY_COLUMNS})
    with outputs:
        with atomic_write(path) as handle:
            handle.write(text.getvalue())
        if parquet:
            _write_parquet(path.with_name(SUMMARY_PARQUET), text.getvalue())


def _has_pyarrow() -> bool:
    """Whether pyarrow (the ``parquet`` extra) can be imported, without importing it."""
    import importlib.util

    return importlib.util.find_spec("pyarrow") is not None


def _row_inputs(row: BatchRow) -> list[tuple[str, str]]:
    """The files a row reads, each with what it is: its route, its vehicle file, its terrain
    files (a folder of tiles as its files)."""
    from .io.tiles import terrain_files

    found = [(row.route, f"the route of row '{row.id}'")]
    for key, value in row.options:
        if key == "vehicle" and names_vehicle_file(value):
            found.append((value, f"the vehicle file of row '{row.id}'"))
        elif key == "terrain":
            parts = [part for part in value.split(";") if part]
            try:
                files = [str(file) for file in terrain_files(parts)]
            except InputError:
                files = parts  # the plan will say what is wrong
            found += [(file, f"a terrain file of row '{row.id}'") for file in files]
    return found


def _check_outputs(rows: Sequence[BatchRow], out: Path, read: list[tuple[str, str, str | None]]) -> None:
    """Refuse, before any work, an output of the batch that is a file it reads (one line
    naming both): the summary that is any of them, a row's profile that is the manifest or
    another row's input (its own route is that row's failure, as ``profileopt plan``'s)."""
    from .io.atomic import file_identity

    if not out.is_dir():
        return  # a new folder: nothing in it is read
    owners: dict[tuple, list[tuple[str, str, str | None]]] = {}
    for path, what, row_id in read:
        owners.setdefault(file_identity(path), []).append((path, what, row_id))
    if not owners:
        return
    for name in (SUMMARY_FILE, SUMMARY_PARQUET):
        found = owners.get(file_identity(out / name))
        if found:
            path, what = found[0][:2]
            raise InputError(f"{out / name}: the batch's summary would replace {what} ({path}); choose another "
                             "output folder")
    for row in rows:
        target = out / f"{row.id}.csv"
        others = [found for found in owners.get(file_identity(target), []) if found[2] != row.id]
        if others:
            path, what = others[0][:2]
            raise InputError(f"{target}: the profile of row '{row.id}' would replace {what} ({path}); give the row "
                             "another id or choose another output folder")


#: The summary's numeric columns and their Parquet types (the others are strings).
_NUMBERS = {"travel_time_s": "float64", "distance_m": "float64", "mean_speed_mps": "float64", "segments": "int64",
            "force_ratio": "float64"}


def _write_parquet(path: Path, summary_csv: str) -> None:
    """The summary as Parquet (typed columns; empty cells null), atomically; nothing without
    pyarrow. Read from the summary's CSV text by pyarrow's own CSV reader, with every column's
    type given: building the columns from Python lists (``pyarrow.array``) imports pandas
    where it is installed, 0.2 s of every batch."""
    try:
        import pyarrow as pa
        import pyarrow.csv as pa_csv
        import pyarrow.parquet as pq
    except ImportError:
        return
    from .io.atomic import atomic_path

    types = {key: getattr(pa, _NUMBERS.get(key, "string"))() for key in SUMMARY_COLUMNS}
    table = pa_csv.read_csv(pa.BufferReader(summary_csv.encode("utf-8")),
                            parse_options=pa_csv.ParseOptions(newlines_in_values=True),
                            convert_options=pa_csv.ConvertOptions(column_types=types, null_values=[""],
                                                                  strings_can_be_null=True))
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp)
