"""``python -m profileopt``: the same as the ``profileopt`` command."""

import sys

from .cli import main

sys.exit(main())
