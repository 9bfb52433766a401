"""Package boundaries and the command line."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import arlequin
from arlequin.cli.main import main

ROOT = Path(arlequin.__file__).resolve().parent


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            mod = node.module or ""
            out.add("." * node.level + mod)
    return out


def test_core_never_imports_the_models():
    offenders = []
    for path in ROOT.rglob("*.py"):
        rel = path.relative_to(ROOT)
        if rel.parts[0] in ("demos", "cli"):
            continue
        for name in _imports(path):
            if "models" in name.split("."):
                offenders.append(f"{rel}: {name}")
    assert not offenders, offenders


def test_models_are_shipped_as_arlequin_models():
    import arlequin.models as models

    assert Path(models.__file__).resolve().parent.name == "models"
    assert hasattr(models, "LinearElastic")


def test_cli_patch_test_writes_json(tmp_path, capsys):
    out = tmp_path / "pt.json"
    assert main(["patch-test", "--dim", "1", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    for key in ("max_error", "exact_residual", "n_coarse_dofs", "n_fine_dofs", "n_multipliers"):
        assert key in data
    assert data["max_error"] <= 1e-10  # exact configuration (1D nested ramp, coarse mediator)
    assert "max_error" in capsys.readouterr().out


def test_cli_reports_errors_cleanly(capsys):
    assert main(["patch-test", "--dim", "3", "--layout", "strip"]) == 2  # a 2D-only layout
    assert "error" in capsys.readouterr().err


def test_console_script_entry_point():
    r = subprocess.run(
        [sys.executable, "-m", "arlequin.cli.main", "patch-test", "--dim", "1"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert r.returncode == 0, r.stderr
    assert "max_error" in r.stdout


def test_models_import_from_the_repository_root_without_the_installed_mapping():
    """From the source tree (as after ``pip install .`` run in the repository root, where the
    local ``arlequin/`` shadows the installed package), ``arlequin.models`` is the sibling
    ``models/`` folder. Simulated here by dropping the editable install's finders."""
    root = ROOT.parent
    code = (
        "import sys\n"
        "sys.meta_path = [f for f in sys.meta_path if 'ditable' not in "
        "getattr(f, '__name__', type(f).__name__) and 'ditable' not in "
        "getattr(f, '__module__', '')]\n"
        f"sys.path.insert(0, {str(root)!r})\n"
        "import arlequin.models, arlequin.models.contact.level_set\n"
        "print(arlequin.__file__)\n"
        "print(arlequin.models.__file__)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert r.returncode == 0, r.stderr
    pkg, models = r.stdout.split()
    assert Path(pkg) == root / "arlequin" / "__init__.py"
    assert Path(models) == root / "models" / "__init__.py"


def test_version_and_info(tmp_path, capsys):
    import json

    import pytest

    import arlequin
    from arlequin.cli.main import main

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"arlequin {arlequin.__version__}"
    path = tmp_path / "info.json"
    assert main(["info", "--no-render", "--json", str(path)]) == 0
    report = json.loads(path.read_text())
    assert report["versions"]["arlequin"] == arlequin.__version__
    assert report["versions"]["numpy"] and report["numba_threads"] >= 1
    assert "numba threads" in capsys.readouterr().out


def test_progress_bar_shows_in_a_terminal():
    # a pseudo-terminal as stderr: tqdm draws the bar there (it stays off in pipes and logs)
    import fcntl
    import os
    import pty
    import struct
    import subprocess
    import sys
    import termios

    master, slave = pty.openpty()
    # a terminal of 24 x 100 characters (a pty has none by default, and tqdm draws nothing)
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))
    proc = subprocess.Popen(
        [sys.executable, "-m", "arlequin.cli.main", "taylor-bar", "--model", "mono",
         "--elements-radial", "3", "--t-end", "3e-6"],
        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=slave,
    )  # fmt: skip
    os.close(slave)
    out = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        out += chunk
    assert proc.wait(timeout=120) == 0
    os.close(master)
    text = out.decode("utf-8", "replace")
    assert "simulated time" in text and "3.0/3.0 µs" in text and "100%" in text


def test_numba_caches_the_kernels_outside_the_package(tmp_path):
    """The compiled kernels' cache lives in the per-user cache directory (or NUMBA_CACHE_DIR),
    never in the installed package (a leftover cache folder there shadowed ``arlequin.models``
    after an uninstall, and a read-only installation could not write it)."""
    code = (
        "import arlequin\n"
        "from arlequin.models.plasticity import j2_kernel\n"
        "from arlequin.geometry import clip3d\n"
        "print(j2_kernel.planar_j2_kernel._cache._cache_path)\n"
        "print(clip3d._clip_one._cache._cache_path)\n"
    )
    env = {k: v for k, v in __import__("os").environ.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    r = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=False
    )
    assert r.returncode == 0, r.stderr
    for line in r.stdout.split():
        path = Path(line).resolve()
        assert path.is_relative_to(tmp_path / "arlequin" / "numba"), path
        assert not path.is_relative_to(ROOT.parent), path
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "given")
    r = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=False
    )
    assert all(Path(p).is_relative_to(tmp_path / "given") for p in r.stdout.split()), r.stdout
