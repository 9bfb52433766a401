"""The configurations of the small demos (patch-test, two-bars, wave; block impact): the inputs
recorded by a tiny run are plain JSON with the expected keys and units, and a bad value gives
the same ``ValueError`` from the command line, a study and Python, before any work."""

from __future__ import annotations

import json

import pytest

from arlequin.cli.main import main
from arlequin.demos.block_impact import BlockImpactConfig, run_block_impact
from arlequin.demos.patch_test import PatchTestConfig, run_patch_test
from arlequin.demos.two_bars import TwoBarsConfig, run_two_bars
from arlequin.demos.wave import WaveConfig, run_wave

PATCH_KEYS = ["dim", "coupling", "weights", "mediator", "mesh", "seed", "layout", "ratio",
              "band_cells"]  # fmt: skip
TWO_BARS_KEYS = ["method", "newmark", "lengths", "young", "density", "velocity", "velocity2",
                 "elements", "cfl", "theta", "t_end", "integrator"]  # fmt: skip
WAVE_KEYS = ["ratio", "pulse_width", "gluing_width", "coupling", "mediator", "weights",
             "integrator", "dt", "epsilon", "length"]  # fmt: skip


def _plain(value) -> bool:
    if isinstance(value, dict):
        return all(isinstance(k, str) and _plain(v) for k, v in value.items())
    if isinstance(value, list):
        return all(_plain(v) for v in value)
    return value is None or isinstance(value, (str, int, float, bool))


@pytest.mark.parametrize(
    "config,keys",
    [(PatchTestConfig(), PATCH_KEYS), (TwoBarsConfig(), TWO_BARS_KEYS), (WaveConfig(), WAVE_KEYS)],
)
def test_configuration_inputs_are_plain_json(config, keys):
    inputs = config.inputs()
    assert list(inputs) == keys
    assert _plain(inputs) and json.loads(json.dumps(inputs)) == inputs
    assert set(config.units()) == set(keys)


@pytest.mark.parametrize(
    "argv,keys,units",
    [
        (["patch-test", "--dim", "1"], PATCH_KEYS, {"seed": "1", "band_cells": "coarse cells"}),
        (["two-bars", "--elements", "10"], TWO_BARS_KEYS,
         {"lengths": "m", "young": "Pa", "t_end": "s", "method": ""}),
        (["wave", "--ratio", "1", "--pulse-width", "4", "--gluing-width", "2"], WAVE_KEYS,
         {"ratio": "1", "dt": "s", "pulse_width": "coarse elements"}),
    ],
)  # fmt: skip
def test_tiny_run_records_its_inputs(tmp_path, argv, keys, units):
    out, js = tmp_path / "run", tmp_path / "run.json"
    assert main([*argv, "--out", str(out), "--json", str(js), *(
        ["--quiet"] if argv[0] != "patch-test" else [])]) == 0  # fmt: skip
    meta = json.loads((out / "results.json").read_text())
    inputs = meta["inputs"]
    assert set(inputs) == set(keys)
    assert _plain(inputs)
    for key, unit in units.items():
        assert inputs[key]["unit"] == unit, key
    data = json.loads(js.read_text())
    if argv[0] == "patch-test":
        first = ["max_error", "exact_residual", "n_coarse_dofs", "n_fine_dofs", "n_multipliers"]
        assert list(data)[:5] == first
    if argv[0] == "two-bars":  # the end time as run, not the default's None
        assert inputs["t_end"]["value"] > 0.0 and inputs["lengths"]["value"] == [1.0, 1.0]


@pytest.mark.parametrize(
    "argv,python,needle",
    [
        (["patch-test", "--seed", "-1"], lambda: run_patch_test(seed=-1),
         "seed must be a non-negative integer, got seed=-1"),
        (["patch-test", "--layout", "strip", "--dim", "3"],
         lambda: run_patch_test(layout="strip", dim=3), "layout='strip' is a 2D"),
        (["two-bars", "--density", "0"], lambda: run_two_bars(density=0.0),
         "density must be positive, got density=0.0"),
        (["two-bars", "--velocity", "-1"], lambda: run_two_bars(velocity=-1.0),
         "bar 1 must approach bar 2"),
        (["two-bars", "--theta", "0.2"], lambda: run_two_bars(theta=0.2),
         "theta must lie in [1/2, 1], got theta=0.2"),
        (["wave", "--ratio", "0"], lambda: run_wave(ratio=0),
         "mesh ratio must be a positive integer, got ratio=0"),
        (["wave", "--dt", "-1"], lambda: run_wave(dt=-1.0),
         "time step dt (s) must be positive and finite, got dt=-1.0"),
    ],
)  # fmt: skip
def test_bad_value_same_error_from_cli_and_python(argv, python, needle, capsys, monkeypatch):
    import importlib

    def no_run(*args, **kwargs):  # nothing may be built or solved before the check
        raise AssertionError("a run started before the inputs were checked")

    for demo in ("patch_test", "two_bars", "wave"):
        for module in ("api", "run"):
            mod = importlib.import_module(f"arlequin.demos.{demo}.{module}")
            monkeypatch.setattr(mod, "run_config", no_run)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert needle in err, err
    with pytest.raises(ValueError) as caught:
        python()
    assert needle in str(caught.value)
    assert str(caught.value) in err


def test_study_checks_with_the_configuration():
    from arlequin.demos.study import StudyError, load_spec

    with pytest.raises(StudyError, match="epsilon must be finite"):
        load_spec({"demo": "wave", "parameters": {"epsilon": float("nan")}})
    with pytest.raises(StudyError, match=r"theta must lie in \[1/2, 1\]"):
        load_spec({"demo": "two-bars", "parameters": {"theta": [0.5, 0.2]}})
    with pytest.raises(StudyError, match="layout='square' is a 2D"):
        load_spec({"demo": "patch-test", "parameters": {"layout": "square", "dim": "3"}})


def test_block_impact_configuration():
    with pytest.raises(ValueError, match="dim must be 2 or 3, got 1"):
        run_block_impact(dim=1)
    with pytest.raises(ValueError, match="target must be 'plane' or 'block'"):
        BlockImpactConfig(target="wall")
    assert _plain(BlockImpactConfig().inputs())
