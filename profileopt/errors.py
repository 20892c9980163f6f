"""The one exception type for a user's mistake.

Every problem with what a user handed over (a file, a key, a column, an option) raises
:class:`InputError`, a subclass of :class:`ValueError`, whose message is one line that
names the file, the line or key, what is wrong and how to fix it. The command line prints
that line and exits with status 2; nothing else is ever shown as a user error.
"""

from __future__ import annotations

__all__ = ["InputError", "InfeasibleError", "PlanningError"]


class InputError(ValueError):
    """A user's input is wrong; the message is a single line that says how to fix it."""


class InfeasibleError(InputError):
    """The route, vehicle and options admit no profile that keeps every limit.

    This is an input problem (the user asked for the impossible), so it is an
    :class:`InputError`; the message says which segment or option makes it so.
    """


class PlanningError(RuntimeError):
    """The solver failed and no profile keeping every limit could be built.

    Not the user's mistake (that is an :class:`InputError`): please report it with the
    route and the vehicle.
    """
