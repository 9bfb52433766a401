"""The worked pages on extending the library (docs/adding-a-*.md) run as written.

Each page's fenced ``python`` blocks are executed in order, in one namespace a page, in a
temporary directory (the demo page writes its JSON and results folder there). The pages hold
their own ``assert`` statements against exact answers; this test only runs them. An integrator
the solver page registers is taken out of the registry afterwards.
"""

from __future__ import annotations

import re
import sys
import types
from pathlib import Path

import pytest

from arlequin.solvers import REGISTRY

DOCS = Path(__file__).resolve().parent.parent / "docs"
PAGES = ("adding-a-demo.md", "adding-a-material.md", "adding-a-solver.md")
_BLOCK = re.compile(r"^```python\n(.*?)^```", re.MULTILINE | re.DOTALL)


def python_blocks(page: Path) -> list[str]:
    """The source of the fenced ``python`` blocks of a Markdown page, in order."""
    return _BLOCK.findall(page.read_text(encoding="utf-8"))


@pytest.mark.parametrize("name", PAGES)
def test_page_code_runs(name, tmp_path, monkeypatch):
    page = DOCS / name
    blocks = python_blocks(page)
    assert blocks, f"{name} has no python block"
    monkeypatch.chdir(tmp_path)
    registered = dict(REGISTRY)
    # one module a page, known to sys.modules as a script's would be (dataclasses look it up)
    module = types.ModuleType(f"docs_{page.stem.replace('-', '_')}")
    sys.modules[module.__name__] = module
    try:
        for k, source in enumerate(blocks):
            code = compile(source, f"{page}[block {k + 1}]", "exec", dont_inherit=True)
            exec(code, module.__dict__)
    finally:
        del sys.modules[module.__name__]
        REGISTRY.clear()
        REGISTRY.update(registered)


@pytest.mark.parametrize("name", PAGES)
def test_page_in_toctree(name):
    index = (DOCS / "index.md").read_text(encoding="utf-8")
    assert re.search(rf"^{re.escape(Path(name).stem)}$", index, re.MULTILINE), name
