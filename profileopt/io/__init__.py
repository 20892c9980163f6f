"""Reading and writing files: routes, profiles, measured terrain, and atomic outputs.

- :mod:`~profileopt.io.table`: the one CSV table reader behind route and profile files;
- :mod:`~profileopt.io.routes`: route files (:func:`read_route`);
- :mod:`~profileopt.io.profiles`: profile files (:func:`read_profile`, :func:`write_profile`);
- :mod:`~profileopt.io.atomic`: outputs that appear whole or not at all
  (:func:`atomic_write`, :func:`atomic_path`, :func:`check_output_paths`);
- :mod:`~profileopt.io.las`: ASPRS LAS point clouds (:func:`read_las`);
- :mod:`~profileopt.io.elevation`: measured elevation profiles (:func:`read_opencrg`,
  :func:`read_xy_profile`).
"""

from .atomic import OutputSet, atomic_path, atomic_write, check_output_path, check_output_paths
from .elevation import read_opencrg, read_xy_profile
from .las import LAS_GROUND, LasHeader, PointCloud, read_las
from .profiles import PROFILE_COLUMNS, read_profile, write_profile
from .routes import read_route
from .table import Table, read_table, split_lines

__all__ = [
    "atomic_path", "atomic_write", "check_output_path", "check_output_paths", "OutputSet",
    "read_opencrg", "read_xy_profile",
    "LAS_GROUND", "LasHeader", "PointCloud", "read_las",
    "PROFILE_COLUMNS", "read_profile", "write_profile",
    "read_route",
    "Table", "read_table", "split_lines",
]
