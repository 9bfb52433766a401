"""Every public name has a docstring: the functions and classes each module lists in
``__all__`` (defined there, not re-exported), and their public methods (inherited docstrings
count, e.g. a protocol method documented once)."""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import arlequin
import arlequin.models


def _modules() -> list[str]:
    names = ["arlequin", "arlequin.models"]
    names += [m.name for m in pkgutil.walk_packages(arlequin.__path__, "arlequin.")]
    names += [m.name for m in pkgutil.walk_packages(arlequin.models.__path__, "arlequin.models.")]
    # ``__main__`` modules run the command when imported
    return sorted(n for n in set(names) if not n.endswith(".__main__"))


def test_every_public_name_has_a_docstring():
    missing = []
    for name in _modules():
        mod = importlib.import_module(name)
        for n in getattr(mod, "__all__", []):
            obj = getattr(mod, n, None)
            if not (inspect.isfunction(obj) or inspect.isclass(obj)) or obj.__module__ != name:
                continue
            if not inspect.getdoc(obj):
                missing.append(f"{name}.{n}")
            if inspect.isclass(obj):
                for attr, member in vars(obj).items():
                    if attr.startswith("_") or not inspect.isfunction(member):
                        continue
                    if not inspect.getdoc(getattr(obj, attr)):
                        missing.append(f"{name}.{n}.{attr}")
    assert not missing, f"public names without a docstring: {missing}"
