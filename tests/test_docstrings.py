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

Each case is named by the qualified name of the function, so a failure says which one.
``KNOWN_FAILURES`` lists the functions of modules being reorganised elsewhere (issue 9) whose
docstrings do not pass yet; they are strict xfails, so the entry must be removed as soon as
the docstring is fixed.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
from typing import Callable

import pytest

import profileopt

#: Functions allowed to take ``**kwargs``, each with the reason.
KWARGS_ALLOWED: dict[str, str] = {
    # dataclasses.replace underneath: a misspelt field name raises TypeError all the same.
    "profileopt.core.vehicle.Vehicle.replace": "the keywords are the Vehicle's fields (dataclasses.replace)",
}

#: Public functions whose docstrings do not document exactly their parameters yet; strict
#: xfails. Empty: every public function passes. Remove an entry when its docstring is fixed.
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
FUNCTIONS = {name: fn for name, fn in PUBLIC.items() if fn.__qualname__ == fn.__name__}


def _cases(names) -> list:
    return [pytest.param(name, marks=pytest.mark.xfail(strict=True, reason="known: docstring being reorganised"))
            if name in KNOWN_FAILURES else name for name in sorted(names)]


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


def test_the_walk_finds_the_public_api() -> None:
    for name in ("profileopt.physics.forces.force_n", "profileopt.mpc.constraints.force_constraints",
                 "profileopt.physics.speeds.SpeedBands.largest_band_only", "profileopt.planning.planner.plan",
                 "profileopt.terrain.roughness.roughness_index", "profileopt.mpc.codegen.export_c"):
        assert name in PUBLIC
    assert not any(name.startswith("profileopt._") for name in PUBLIC)


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


@pytest.mark.parametrize("qualname", _cases(PUBLIC))
def test_docstring_names_exactly_the_parameters(qualname: str) -> None:
    fn = PUBLIC[qualname]
    expected = signature_parameters(fn)
    documented = documented_parameters(inspect.getdoc(fn))
    if not expected:
        assert not documented, f"{qualname} takes no parameters but documents {documented}"
        return
    assert documented is not None, f"{qualname}{inspect.signature(fn)}: no Parameters section"
    assert len(documented) == len(set(documented)), f"{qualname}: documented twice: {documented}"
    assert set(documented) == set(expected), (
        f"{qualname}: undocumented {sorted(set(expected) - set(documented))}, "
        f"documented but not parameters {sorted(set(documented) - set(expected))}"
    )


@pytest.mark.parametrize("qualname", sorted(PUBLIC))
def test_no_public_function_swallows_keywords(qualname: str) -> None:
    kinds = [p.kind for p in inspect.signature(PUBLIC[qualname]).parameters.values()]
    if qualname not in KWARGS_ALLOWED:
        assert inspect.Parameter.VAR_KEYWORD not in kinds, f"{qualname} takes **kwargs: a misspelt keyword passes"


@pytest.mark.parametrize("qualname", sorted(FUNCTIONS))
def test_a_misspelt_keyword_raises_type_error(qualname: str) -> None:
    if qualname in KWARGS_ALLOWED:
        pytest.skip(KWARGS_ALLOWED[qualname])
    with pytest.raises(TypeError):
        FUNCTIONS[qualname](no_such_keyword_xyz=1)


def test_the_lists_name_only_public_functions() -> None:
    assert not (KNOWN_FAILURES | set(KWARGS_ALLOWED)) - set(PUBLIC), "a stale entry: remove it"
