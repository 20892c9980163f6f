"""Old parameter names and positions that keep working for one release, with a warning.

Issue 9 ("one vocabulary") renamed and reordered parameters of the public API. A function
decorated with :func:`old_forms` accepts its old calls too: an ``adapt`` function rewrites
the call into the new form and says what was old, and the wrapper issues one
``DeprecationWarning`` per call that names the new form, attributed to the caller's line.
``inspect.signature`` of the decorated function is the new signature (it follows
``__wrapped__``), and a misspelt keyword still raises ``TypeError`` from the function.
"""

from __future__ import annotations

import functools
import warnings
from typing import Any, Callable, Sequence

__all__ = ["OldCall", "old_forms"]


class OldCall:
    """A call being rewritten into the new form: ``args``, ``kwargs`` and the notes on
    what was old (each note names the new form to use)."""

    def __init__(self, args: tuple, kwargs: dict) -> None:
        self.args = tuple(args)
        self.kwargs = dict(kwargs)
        self.notes: list[str] = []

    def rename(self, renames: dict[str, str]) -> "OldCall":
        """Move the keywords ``old`` to ``new`` for each ``old: new`` of ``renames``."""
        for old, new in renames.items():
            if old in self.kwargs:
                if new in self.kwargs:
                    raise TypeError(f"got both {old}= (deprecated) and {new}=; pass only {new}=")
                self.kwargs[new] = self.kwargs.pop(old)
                self.notes.append(f"the keyword {old}= is deprecated, use {new}=")
        return self

    def move(self, start: int, names: Sequence[str], note: str | None = "") -> "OldCall":
        """Turn the positional arguments from index ``start`` on into the keywords ``names``
        (in order). If there were any, add ``note``: by default "pass <names>= by keyword"
        for the names moved, None for none."""
        extra = self.args[start:]
        if not extra:
            return self
        if len(extra) > len(names):
            raise TypeError(f"takes at most {start + len(names)} positional arguments in its old form "
                            f"({len(self.args)} given)")
        self.args = self.args[:start]
        for name, value in zip(names, extra):
            if name in self.kwargs:
                raise TypeError(f"got multiple values for argument {name!r}")
            self.kwargs[name] = value
        if note == "":
            note = "pass " + ", ".join(f"{name}=" for name in names[:len(extra)]) + " by keyword"
        if note is not None:
            self.notes.append(note)
        return self

    def model_first(self, rest: Sequence[str], note: str) -> bool:
        """The old form ``f(model, *rest)``, a ``str`` model first: move ``model`` and the
        arguments after the first ``rest`` one (which stays positional) to keywords."""
        if not (self.args and isinstance(self.args[0], str)):
            return False
        if "model" in self.kwargs:
            raise TypeError("got multiple values for argument 'model'")
        self.kwargs["model"] = self.args[0]
        self.args = self.args[1:]
        self.move(1, rest[1:], None)
        self.notes.append(note)
        return True


def old_forms(adapt: Callable[[OldCall], Any]) -> Callable[[Callable], Callable]:
    """Decorate a function so that ``adapt(call)`` may rewrite an old call into the new one.

    ``adapt`` receives an :class:`OldCall` and edits it in place (``rename``, ``move`` or its
    ``args``/``kwargs`` and ``notes`` directly). If it added notes, the wrapper warns once
    with all of them (``DeprecationWarning``, pointing at the caller) and then calls the
    function with the rewritten arguments.
    """

    def decorate(func: Callable) -> Callable:
        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            call = OldCall(args, kwargs)
            adapt(call)
            if call.notes:
                warnings.warn(f"{func.__name__}(): " + "; ".join(call.notes) + " (old forms are removed in the next "
                              "release)", DeprecationWarning, stacklevel=2)
            return func(*call.args, **call.kwargs)

        return wrapper

    return decorate
