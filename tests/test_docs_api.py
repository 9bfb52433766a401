"""docs/api.md says where each documented name lives: every row is importable as written."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import arlequin
import arlequin.models

API = Path(__file__).resolve().parent.parent / "docs" / "api.md"


def rows():
    for line in API.read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 3 or not cells[0].startswith("`"):
            continue
        names = re.findall(r"`([A-Za-z_][A-Za-z0-9_]*)`", cells[0])
        modules = re.findall(r"`(arlequin[a-z0-9_.]*)`", cells[1])
        yield names, modules, cells[1]


def test_every_documented_name_lives_where_the_page_says():
    missing = []
    for names, modules, where in rows():
        assert modules, where
        # a parenthesis "(`x` also `arlequin`)" lists extra places for some of the names only
        main, _, extra = where.partition("(")
        main_modules = re.findall(r"`(arlequin[a-z0-9_.]*)`", main)
        extra_names = re.findall(r"`([A-Za-z_][A-Za-z0-9_]*)`", extra)
        for name in names:
            for mod in main_modules:
                if not hasattr(importlib.import_module(mod), name):
                    missing.append((name, mod))
        extra_modules = [m for m in re.findall(r"`(arlequin[a-z0-9_.]*)`", extra)]
        for name in extra_names:
            if name.startswith("arlequin"):
                continue
            for mod in extra_modules:
                if not hasattr(importlib.import_module(mod), name):
                    missing.append((name, mod))
    assert not missing, missing


def test_public_names_are_documented():
    page = API.read_text(encoding="utf-8")
    for module in (arlequin, arlequin.models):
        undocumented = [n for n in module.__all__ if f"`{n}`" not in page]
        assert not undocumented, (module.__name__, undocumented)
