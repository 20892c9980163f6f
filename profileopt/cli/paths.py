"""What the sub-commands share about their files: which arguments are input files, and the
outputs of a command that writes into a folder."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Iterable

from ..errors import InputError

if TYPE_CHECKING:
    from ..io.atomic import OutputSet


def vehicle_input(name_or_path: str | None) -> str | None:
    """The file a ``--vehicle`` argument reads, if it names a file (the rule of
    :func:`profileopt.load_vehicle`: a path ends in .toml or has a folder in it); None for a
    bundled name."""
    from ..core.vehicle import names_vehicle_file  # no numerical package: fine for --help

    return name_or_path if name_or_path is not None and names_vehicle_file(name_or_path) else None


def check_folder(label: str, folder: str) -> Path:
    """Refuse an empty folder path or one that exists and is not a folder."""
    if not folder:
        raise InputError(f"{label} '': the output folder is empty; give the path of a folder")
    path = Path(folder)
    if path.exists() and not path.is_dir():
        raise InputError(f"{label} {path}: exists and is not a folder; give a folder path")
    return path


def folder_outputs(label: str, files: Iterable[Path], inputs: Iterable[str | None]) -> OutputSet | None:
    """An :class:`OutputSet` of the files a command writes into one folder, checked now if the
    folder exists (None if it does not: then no file in it exists or is an input yet)."""
    from ..io.atomic import (
        OutputSet,  # imported when the command runs, not for --help (issue 14)
    )

    files = list(files)
    if not files or not os.path.isdir(files[0].parent):
        return None
    return OutputSet([(label, path) for path in files], inputs=inputs)
