"""Sphinx configuration of the arlequin documentation (``python -m sphinx -W -b html docs
docs/_build/html``; the pages are Markdown through MyST, the API reference comes from the
numpydoc docstrings)."""

from __future__ import annotations

import ast
from pathlib import Path

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


# ---------------------------------------------------------------------------- gallery of examples
# One page per script of examples/ (its docstring, the pictures it names in GALLERY_IMAGES,
# relative to docs/, and its code), generated at each build into docs/examples/ (not versioned):
# the gallery is built from the examples, never written by hand beside them.
_DOCS = Path(__file__).resolve().parent
_EXAMPLES = _DOCS.parent / "examples"
_PAGES = _DOCS / "examples"


def _example_page(script: Path) -> str:
    module = ast.parse(script.read_text(encoding="utf-8"))
    doc = ast.get_docstring(module) or script.stem
    images: list[str] = []
    for node in module.body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "GALLERY_IMAGES" for t in node.targets
        ):
            images = list(ast.literal_eval(node.value))
    first, _, rest = doc.partition("\n\n")
    lines = [
        f"# {' '.join(first.split())}",
        "",
        rest.strip(),
        "",
        f"Run it: `python examples/{script.name}`.",
        "",
    ]
    for img in images:
        lines += [f"![{Path(img).stem}](../{img})", ""]
    lines += [f"```{{literalinclude}} ../../examples/{script.name}", ":language: python", "```", ""]
    return "\n".join(lines)


def _write_gallery(app=None) -> None:
    _PAGES.mkdir(exist_ok=True)
    wanted = {}
    for script in sorted(_EXAMPLES.glob("*.py")):
        wanted[_PAGES / f"{script.stem}.md"] = _example_page(script)
    for page in _PAGES.glob("*.md"):
        if page not in wanted:
            page.unlink()
    for page, text in wanted.items():
        if not page.exists() or page.read_text(encoding="utf-8") != text:
            page.write_text(text, encoding="utf-8")  # unchanged pages keep their time stamp


def setup(app):
    app.connect("builder-inited", _write_gallery)
    return {"parallel_read_safe": True}
