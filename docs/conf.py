"""Sphinx configuration of the profileopt documentation.

Build (warnings are errors, as in CI):

    python -m sphinx -W --keep-going -b html docs docs/_build/html

Pages are MyST Markdown; the API reference is generated from the numpy-style docstrings by
autodoc, autosummary (one page per module, found recursively) and numpydoc.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

# The documentation is of the checkout it sits in, installed or not.
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
os.environ.setdefault("MPLBACKEND", "Agg")

import profileopt  # noqa: E402

project = "profileopt"
author = "the profileopt authors"
copyright = "the profileopt authors"  # noqa: A001
version = release = profileopt.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]
templates_path = ["_templates"]

# MyST: headings get anchors so that pages can link to a section ("page.md#section").
myst_heading_anchors = 3
myst_enable_extensions: list[str] = []

# API reference: one page per module, generated into api/generated/ at every build.
autosummary_generate = True
autosummary_imported_members = False
autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the numpy-style docstrings give every type

numpydoc_show_class_members = False  # autodoc lists the members
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()

# Cross-references that find nothing stay plain text (the docstrings name many things that
# are not documented objects: CasADi types, numpy arrays, private helpers).
nitpicky = False

html_theme = "pydata_sphinx_theme"
html_title = f"profileopt {release}"
html_static_path: list[str] = []
html_theme_options = {
    "navigation_depth": 3,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
}
# Pages without children need no left-hand navigation.
html_sidebars = {
    "**": ["sidebar-nav-bs"],
    "index": [],
    "getting-started": [],
    "architecture": [],
    "paper-notes": [],
}


# The docstrings write absolute values as in plain text, |v da/ds| <= J, which reStructuredText
# reads as a substitution reference. Escape such pairs of bars (outside literals, doctests and
# literal blocks) before numpydoc and docutils see them.
_LITERAL = re.compile(r"(``.+?``|`[^`]+`)")
_BARS = re.compile(r"(?<![\\\w|])\|(?=[^\s|])([^|\n]*?[^\s\\|])\|(?![\w|])")


def _escape_bars(text: str) -> str:
    parts = _LITERAL.split(text)
    for i in range(0, len(parts), 2):  # the even parts are outside literals
        parts[i] = _BARS.sub(r"\\|\1\\|", parts[i])
    return "".join(parts)


def _plain_bars(app, what, name, obj, options, lines: list[str]) -> None:
    literal_indent = None  # inside a literal block: the indentation of its introducing line
    previous = previous_line = ""
    for i, line in enumerate(lines):
        stripped = line.strip()
        indent = len(line) - len(line.lstrip())
        if literal_indent is not None:
            if not stripped or indent > literal_indent:
                continue
            literal_indent = None
        if previous.endswith("::") and not stripped:
            literal_indent = len(previous_line) - len(previous_line.lstrip())
            continue
        if stripped:
            previous, previous_line = stripped, line
        if stripped.startswith((">>>", "...")):
            continue
        lines[i] = _escape_bars(line)


# benchmarks/README.md and benchmarks/results.md are included as pages here; their links to
# each other point at those pages.
_INCLUDED_LINKS = {"](results.md)": "](benchmark-results.md)", "](README.md)": "](benchmarks.md)"}


def _included_links(app, relative_path, parent_docname, content: list[str]) -> None:
    if Path(relative_path).parent.name == "benchmarks":
        for old, new in _INCLUDED_LINKS.items():
            content[0] = content[0].replace(old, new)


def setup(app):
    app.connect("autodoc-process-docstring", _plain_bars, priority=400)
    app.connect("include-read", _included_links)
