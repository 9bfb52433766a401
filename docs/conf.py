"""Sphinx configuration of the arlequin documentation (``python -m sphinx -W -b html docs
docs/_build/html``; the pages are Markdown through MyST, the API reference comes from the
numpydoc docstrings)."""

from __future__ import annotations

import arlequin

project = "arlequin"
author = "the arlequin developers"
release = arlequin.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "numpydoc",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3
exclude_patterns = ["_build"]
root_doc = "index"

autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_validation_checks: set[str] = set()
numpydoc_xref_param_type = False

html_theme = "alabaster"
html_title = f"arlequin {release}"
suppress_warnings = ["myst.header"]
