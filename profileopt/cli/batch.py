"""``profileopt batch``: plan many routes at once, each as ``profileopt plan`` plans it.

The work is :func:`profileopt.batch.plan_many`; this module reads the command line, says
what was done and sets the exit status (:data:`EXIT_SOME_FAILED` when a row failed).
"""

from __future__ import annotations

import argparse
import os
import sys

from ..errors import InputError
from .track import whole_number_argument

#: The exit status when some routes failed (the others were planned; the summary lists the
#: failures with their one-line errors).
EXIT_SOME_FAILED = 5


def arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = ("exit status: 0 every route planned; 2 bad input (the manifest, an option); "
                     f"{EXIT_SOME_FAILED} some routes failed (summary.csv gives each one's error); 1 internal error. "
                     "Run again to plan only what is missing, failed or changed.")
    parser.add_argument("routes", nargs="*", metavar="ROUTE",
                        help="route files (or tracks) planned with the options below; or give --manifest")
    parser.add_argument("--manifest", metavar="CSV_OR_JSON",
                        help="one row per route: columns id, route and any long option of 'profileopt plan' "
                             "without its dashes (terrain, vehicle, model, segment_length, ...); relative paths "
                             "are relative to the manifest")
    parser.add_argument("-o", "--out", required=True, metavar="DIR",
                        help="the output folder: ID.csv per route (the profile 'profileopt plan -o' writes) and "
                             "summary.csv (created if missing)")
    parser.add_argument("--vehicle", metavar="NAME_OR_TOML", help="with ROUTE files: the vehicle of every route")
    parser.add_argument("--model", metavar="MODEL", help="with ROUTE files: the force model of every route")
    parser.add_argument("--terrain", metavar="FILE", nargs="+", action="extend",
                        help="with ROUTE files (tracks): the ground under every track, a terrain file, tiles or a "
                             "folder of them (each route reads only the tiles near it, on its worker)")
    parser.add_argument("--workers", type=_workers, default=None, metavar="N",
                        help="worker processes of the local Dask cluster (default: the machine's cores); 1: one "
                             "route after another in this process, without Dask")
    parser.add_argument("--scheduler", default=os.environ.get("DASK_SCHEDULER_ADDRESS"), metavar="ADDRESS",
                        help="plan on a running Dask cluster: its scheduler's address, tcp://HOST:PORT (default: "
                             "$DASK_SCHEDULER_ADDRESS, else a local cluster)")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress display on stderr")


def run(args: argparse.Namespace) -> int:
    from ..batch import SUMMARY_FILE, BatchRow, plan_many, read_manifest
    from ..progress import terminal_progress

    if (args.manifest is None) == (not args.routes):
        raise InputError("give either --manifest FILE or route files, not both and not neither")
    _refuse_names_not_in_utf8(args)
    if args.manifest is not None:
        if args.vehicle or args.model or args.terrain:
            raise InputError("--vehicle, --model and --terrain apply to route files; in a manifest they are its "
                             "columns")
        rows = read_manifest(args.manifest)
    else:
        terrain = ";".join(args.terrain) if args.terrain else None
        common = tuple((name, value) for name, value in (("vehicle", args.vehicle), ("model", args.model),
                                                          ("terrain", terrain)) if value)
        stems = [os.path.splitext(os.path.basename(route))[0] for route in args.routes]
        if len(set(stems)) != len(stems):
            raise InputError("two route files have the same name; give a manifest with an id for each")
        rows = [BatchRow(stem, route, common) for stem, route in zip(stems, args.routes)]
    with terminal_progress("profileopt batch", enabled=not args.quiet) as progress:
        summary = plan_many(rows, args.out, workers=args.workers, scheduler=args.scheduler, progress=progress,
                            inputs=[args.manifest] if args.manifest is not None else [])
    failed = [row for row in summary if row["status"] != "ok"]
    for row in failed:
        print(f"profileopt batch: {row['id']}: {row['error']}", file=sys.stderr)
    print(f"planned {len(summary) - len(failed)} of {len(summary)} routes into {args.out} "
          f"({os.path.join(args.out, SUMMARY_FILE)})" + (f"; {len(failed)} failed" if failed else ""))
    return EXIT_SOME_FAILED if failed else 0


def _refuse_names_not_in_utf8(args: argparse.Namespace) -> None:
    """Refuse a file or folder name that is not UTF-8 (Python keeps its bytes as lone
    surrogates): the batch writes every name into its summary and its cache keys, which
    must be text."""
    from .messages import printable

    names = [("--out", args.out), ("--manifest", args.manifest), *(("a route", route) for route in args.routes),
             *(("--terrain", terrain) for terrain in args.terrain or ())]
    for what, name in names:
        if name is None:
            continue
        try:
            name.encode("utf-8")
        except UnicodeEncodeError:
            raise InputError(f"{printable(name)}: the name of {what} has bytes that are not UTF-8 (shown as U+FFFD); "
                             "batch writes every name into its summary as text: rename it, or plan it alone with "
                             "'profileopt plan'") from None


def _workers(text: str) -> int:
    """A whole number >= 1 for --workers, or argparse's one-line error."""
    return whole_number_argument(text, minimum=1, what="a number of workers")
