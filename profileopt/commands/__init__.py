"""Sub-commands of the ``profileopt`` command line, one module each.

Each module registers itself with :func:`profileopt.cli.command` when imported; add a new
sub-command by writing its module and importing it here.
"""

from . import figures  # noqa: F401
from . import plan  # noqa: F401
from . import route  # noqa: F401
from . import export_c  # noqa: F401
from . import verify  # noqa: F401
