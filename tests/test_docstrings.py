"""Every public function documents exactly its parameters, and none swallows keywords.

In the manner of python-control's ``docstrings_test.py`` and ``kwargs_test.py``: walk
``profileopt`` and its public submodules (no ``_`` in the dotted name), take the names in
each module's ``__all__`` that are defined there (``obj.__module__``; re-exports are checked
where they are defined), and for every function and every public method of every class:

* the numpydoc "Parameters" section names exactly the parameters of
  ``inspect.signature`` (without ``self``/``cls``; ``*args`` and ``**kwargs`` written as
  such; combined lines ``a, b : float`` name both). A function without parameters needs no
  section.
* no signature has ``**kwargs`` (a misspelt keyword must raise ``TypeError``) unless it is
  in ``KWARGS_ALLOWED`` below, with the reason; and calling a public function with an
  unknown keyword does raise ``TypeError`` (the decorated ones too).

Each rule is one test that walks every public function and fails once, listing every
offender as ``qualified.name: problem``, so one run shows all there is to fix. Each rule's
checker is also fed deliberately bad functions (``test_each_checker_reports_every_offender``),
so a checker that stopped finding anything would fail there.
``KNOWN_FAILURES`` lists the functions of modules being reorganised elsewhere (issue 9) whose
docstrings do not pass yet; a listed function that passes is reported too, so the entry is
removed as soon as the docstring is fixed.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
from typing import Callable, Mapping

import profileopt

#: Functions allowed to take ``**kwargs``, each with the reason.
KWARGS_ALLOWED: dict[str, str] = {
    # dataclasses.replace underneath: a misspelt field name raises TypeError all the same.
    "profileopt.core.vehicle.Vehicle.replace": "the keywords are the Vehicle's fields (dataclasses.replace)",
}

#: Public functions whose docstrings do not document exactly their parameters yet. Empty:
#: every public function passes. Remove an entry when its docstring is fixed (a listed
#: function that passes is reported).
KNOWN_FAILURES: set[str] = set()


def _public_modules() -> list[str]:
    names = [profileopt.__name__]
    for info in pkgutil.walk_packages(profileopt.__path__, profileopt.__name__ + "."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    return sorted(names)


def _public_callables() -> dict[str, Callable]:
    found: dict[str, Callable] = {}
    for module_name in _public_modules():
        module = importlib.import_module(module_name)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if getattr(obj, "__module__", None) != module_name:
                continue  # imported from elsewhere: checked where it is defined
            if inspect.isclass(obj):
                for attr, member in vars(obj).items():
                    if attr.startswith("_"):
                        continue
                    if isinstance(member, (staticmethod, classmethod)):
                        member = member.__func__
                    if inspect.isfunction(member):
                        found[f"{module_name}.{name}.{attr}"] = member
            elif inspect.isfunction(obj):
                found[f"{module_name}.{name}"] = obj
    return found


PUBLIC = _public_callables()
#: the plain functions (not methods): those that can be called with a keyword alone
FUNCTIONS = {name: fn for name, fn in PUBLIC.items() if fn.__qualname__ == fn.__name__}


def signature_parameters(fn: Callable) -> list[str]:
    """The parameters of ``fn`` as a docstring names them: ``*args``, ``**kwargs``, no self/cls."""
    out = []
    for i, (name, par) in enumerate(inspect.signature(fn).parameters.items()):
        if i == 0 and name in ("self", "cls") and "." in fn.__qualname__:
            continue
        if par.kind is inspect.Parameter.VAR_POSITIONAL:
            name = "*" + name
        elif par.kind is inspect.Parameter.VAR_KEYWORD:
            name = "**" + name
        out.append(name)
    return out


def _is_underline(line: str) -> bool:
    return re.fullmatch(r"-{3,}", line.strip()) is not None


def documented_parameters(doc: str | None) -> list[str] | None:
    """The names of the numpydoc "Parameters" section of ``doc``; None without a section.

    Every line at the indentation of the section header is an entry, ``name : type`` or
    just ``name``; ``a, b : type`` names both. The section ends at the next header (a line
    followed by a dashed underline).
    """
    if not doc:
        return None
    lines = doc.splitlines()
    for i in range(len(lines) - 1):
        if lines[i].strip() == "Parameters" and _is_underline(lines[i + 1]):
            break
    else:
        return None
    indent = len(lines[i]) - len(lines[i].lstrip())
    names: list[str] = []
    for j in range(i + 2, len(lines)):
        line = lines[j]
        if j + 1 < len(lines) and line.strip() and _is_underline(lines[j + 1]):
            break  # the next section
        if line.strip() and len(line) - len(line.lstrip()) == indent:
            head = line.strip().split(" : ")[0]
            names.extend(part.strip() for part in head.split(","))
    return names


# ------------------------------------------------------------------------------ the checkers
# Each takes {qualified name: function} and returns one "name: problem" line per offence.


def docstring_problem(qualname: str, fn: Callable) -> str | None:
    """What is wrong with the "Parameters" section of ``fn``'s docstring, or None."""
    expected = signature_parameters(fn)
    documented = documented_parameters(inspect.getdoc(fn))
    if not expected:
        return f"takes no parameters but documents {documented}" if documented else None
    if documented is None:
        return f"no Parameters section (signature {inspect.signature(fn)})"
    if len(documented) != len(set(documented)):
        return f"documented twice: {sorted({n for n in documented if documented.count(n) > 1})}"
    if set(documented) != set(expected):
        return (f"undocumented {sorted(set(expected) - set(documented))}, "
                f"documented but not parameters {sorted(set(documented) - set(expected))}")
    return None


def docstring_problems(public: Mapping[str, Callable], known: set[str] = frozenset()) -> list[str]:
    """One line per function whose docstring does not name exactly its parameters; a name in
    ``known`` is expected to fail, and reported if it passes."""
    out = []
    for qualname in sorted(public):
        problem = docstring_problem(qualname, public[qualname])
        if problem and qualname not in known:
            out.append(f"{qualname}: {problem}")
        elif not problem and qualname in known:
            out.append(f"{qualname}: passes now; remove it from KNOWN_FAILURES")
    return out


def kwargs_problems(public: Mapping[str, Callable], allowed: Mapping[str, str] = KWARGS_ALLOWED) -> list[str]:
    """One line per function that takes ``**kwargs`` without an entry in ``allowed``."""
    return [f"{qualname}: takes **kwargs, so a misspelt keyword passes" for qualname in sorted(public)
            if qualname not in allowed and any(p.kind is inspect.Parameter.VAR_KEYWORD
                                               for p in inspect.signature(public[qualname]).parameters.values())]


def misspelt_keyword_problems(functions: Mapping[str, Callable],
                              allowed: Mapping[str, str] = KWARGS_ALLOWED) -> list[str]:
    """One line per function that, called with only an unknown keyword, does not raise TypeError."""
    out = []
    for qualname in sorted(functions):
        if qualname in allowed:
            continue
        try:
            functions[qualname](no_such_keyword_xyz=1)
        except TypeError:
            continue
        except Exception as error:  # noqa: BLE001 -- any other outcome is the offence reported
            out.append(f"{qualname}: a misspelt keyword raised {type(error).__name__}, not TypeError")
        else:
            out.append(f"{qualname}: a misspelt keyword was accepted")
    return out


def _report(problems: list[str], rule: str) -> str:
    return f"{len(problems)} public function(s) break the rule '{rule}':\n  " + "\n  ".join(problems)


# ------------------------------------------------------------------------------ the rules


def test_the_walk_finds_the_public_api() -> None:
    for name in ("profileopt.physics.forces.force_n", "profileopt.mpc.constraints.force_constraints",
                 "profileopt.physics.speeds.SpeedBands.largest_band_only", "profileopt.planning.planner.plan",
                 "profileopt.terrain.roughness.roughness_index", "profileopt.mpc.codegen.export_c"):
        assert name in PUBLIC
    assert not any(name.startswith("profileopt._") for name in PUBLIC)
    assert len(FUNCTIONS) > 100 and len(PUBLIC) > len(FUNCTIONS)


def test_the_parser_reads_combined_and_bare_entries() -> None:
    doc = inspect.cleandoc("""Summary.

    Parameters
    ----------
    a, b : float
        Two numbers.
    c
        As above.
    *args : int
    **kwargs

    Returns
    -------
    x : float
    """)
    assert documented_parameters(doc) == ["a", "b", "c", "*args", "**kwargs"]
    assert documented_parameters("Summary only.") is None


def test_every_docstring_names_exactly_the_parameters() -> None:
    problems = docstring_problems(PUBLIC, KNOWN_FAILURES)
    assert not problems, _report(problems, "the Parameters section names exactly the parameters")


def test_no_public_function_swallows_keywords() -> None:
    problems = kwargs_problems(PUBLIC)
    assert not problems, _report(problems, "no **kwargs")


def test_a_misspelt_keyword_raises_type_error() -> None:
    problems = misspelt_keyword_problems(FUNCTIONS)
    assert not problems, _report(problems, "a misspelt keyword raises TypeError")


def test_the_lists_name_only_public_functions() -> None:
    assert not (KNOWN_FAILURES | set(KWARGS_ALLOWED)) - set(PUBLIC), "a stale entry: remove it"


# ------------------------------------------------------------- the checkers can fail


def _good(a: int, b: int = 0) -> int:
    """Sum.

    Parameters
    ----------
    a, b : int
        The numbers.
    """
    return a + b


def _undocumented(a: int, b: int) -> int:
    """Sum.

    Parameters
    ----------
    a : int
    """
    return a + b


def _extra(a: int) -> int:
    """Identity.

    Parameters
    ----------
    a : int
    c : int
        Not a parameter.
    """
    return a


def _twice(a: int) -> int:
    """Identity.

    Parameters
    ----------
    a : int
    a : int
    """
    return a


def _no_section(a: int) -> int:
    """Identity, its parameter described in prose only."""
    return a


def _nothing_to_document() -> int:
    """A constant.

    Parameters
    ----------
    x : int
    """
    return 0


def _swallows(a: int = 0, **options: int) -> int:
    """Sum.

    Parameters
    ----------
    a : int
    **options : int
    """
    return a + sum(options.values())


def _wrong_error(**kwargs: int) -> None:
    """Refuses everything, with the wrong exception.

    Parameters
    ----------
    **kwargs : int
    """
    raise ValueError(kwargs)


def test_each_checker_reports_every_offender() -> None:
    bad = {"bad.undocumented": _undocumented, "bad.extra": _extra, "bad.twice": _twice,
           "bad.no_section": _no_section, "bad.nothing_to_document": _nothing_to_document}
    problems = docstring_problems({"ok.good": _good, **bad})
    assert [line.split(":")[0] for line in problems] == sorted(bad), problems
    assert "undocumented ['b']" in "\n".join(problems) and "not parameters ['c']" in "\n".join(problems)
    # a known failure that passes is reported; one that still fails is not
    assert docstring_problems({"ok.good": _good, "bad.extra": _extra}, {"ok.good", "bad.extra"}) == [
        "ok.good: passes now; remove it from KNOWN_FAILURES"]

    kwargs = {"ok.good": _good, "bad.swallows": _swallows, "bad.wrong_error": _wrong_error}
    assert [line.split(":")[0] for line in kwargs_problems(kwargs)] == ["bad.swallows", "bad.wrong_error"]
    assert kwargs_problems(kwargs, {"bad.swallows": "why", "bad.wrong_error": "why"}) == []

    assert misspelt_keyword_problems(kwargs) == [
        "bad.swallows: a misspelt keyword was accepted",
        "bad.wrong_error: a misspelt keyword raised ValueError, not TypeError"]
    assert misspelt_keyword_problems(kwargs, {"bad.swallows": "why"}) == [
        "bad.wrong_error: a misspelt keyword raised ValueError, not TypeError"]
