"""Reading and writing files: routes, profiles, measured terrain, and atomic outputs.

- :mod:`~profileopt.io.table`: the one CSV table reader behind route, profile and track CSV
  files (its rule for line ends holds for vehicle files too);
- :mod:`~profileopt.io.routes`: route files (:func:`read_route`);
- :mod:`~profileopt.io.profiles`: profile files (:func:`read_profile`, :func:`write_profile`);
- :mod:`~profileopt.io.atomic`: outputs that appear whole or not at all
  (:func:`atomic_write`, :func:`atomic_path`, :func:`check_output_paths`);
- :mod:`~profileopt.io.las`: ASPRS LAS and LAZ point clouds (:func:`read_las`, via laspy);
- :mod:`~profileopt.io.tracks`: GPS tracks from GPX, GeoJSON and CSV (:func:`read_track`,
  :func:`project_track`, :func:`local_projected_crs`, and the checks before a track is
  sampled: :func:`~profileopt.io.tracks.check_track_samples`,
  :func:`~profileopt.io.tracks.check_not_degrees`);
- :mod:`~profileopt.io.terrain_maps`: raster DEMs and OpenCRG surfaces
  (:func:`read_geotiff`, :func:`read_crg_surface`, :func:`read_terrain`);
- :mod:`~profileopt.io.tiles`: terrain in tiles, several files or a folder read as one
  around a track (:func:`read_tiles`, :class:`GridTiles`);
- :mod:`~profileopt.io.geo`: the optional ``geo`` packages and CRS helpers (:func:`parse_crs`);
- :mod:`~profileopt.io.elevation`: measured elevation profiles (:func:`read_opencrg`,
  :func:`read_xy_profile`).
"""

import importlib
from typing import Any

# Imported when first used (PEP 562): reading a route needs neither SciPy (the elevation
# readers) nor the planner (profile files); name -> module of this package.
_LAZY = {
    "OutputSet": "atomic", "atomic_path": "atomic", "atomic_write": "atomic", "check_output_path": "atomic",
    "check_output_paths": "atomic",
    "read_opencrg": "elevation", "read_xy_profile": "elevation",
    "LAS_GROUND": "las", "LasHeader": "las", "PointCloud": "las", "read_las": "las",
    "parse_crs": "geo",
    "Track": "tracks", "read_track": "tracks", "project_track": "tracks", "local_projected_crs": "tracks",
    "ElevationGrid": "terrain_maps", "CrgSurface": "terrain_maps", "read_geotiff": "terrain_maps",
    "read_crg_surface": "terrain_maps", "read_terrain": "terrain_maps",
    "GridTiles": "tiles", "read_tiles": "tiles",
    "PROFILE_COLUMNS": "profiles", "read_profile": "profiles", "write_profile": "profiles",
    "read_route": "routes",
    "Table": "table", "read_table": "table", "split_lines": "table",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'profileopt.io' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "atomic_path", "atomic_write", "check_output_path", "check_output_paths", "OutputSet",
    "read_opencrg", "read_xy_profile",
    "LAS_GROUND", "LasHeader", "PointCloud", "read_las",
    "parse_crs",
    "Track", "read_track", "project_track", "local_projected_crs",
    "ElevationGrid", "CrgSurface", "read_geotiff", "read_crg_surface", "read_terrain", "GridTiles", "read_tiles",
    "PROFILE_COLUMNS", "read_profile", "write_profile",
    "read_route",
    "Table", "read_table", "split_lines",
]
