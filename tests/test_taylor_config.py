"""The Taylor bar's configuration (arlequin/demos/taylor_bar/config.py): the inputs a run
records are plain JSON with the expected keys and units, and a bad value is the same
``ValueError`` from the command line, a study's check and Python, before any work."""

from __future__ import annotations

import json

import pytest

from arlequin.cli.demos import check_case, demo_parser
from arlequin.cli.main import main
from arlequin.coupling.weights import RampWeights
from arlequin.demos.taylor_bar import TaylorBarConfig, run_taylor_bar
from arlequin.demos.taylor_bar.setup import build_bar, resolve
from arlequin.models import BulkViscosity

#: What a single-mesh run records (bulk viscosity on: its two coefficients too).
MONO_INPUTS = {
    "model", "geometry", "elements_radial", "elements_axial", "mesh_size", "t_end", "velocity",
    "young", "poisson", "density", "yield_stress", "hardening", "hardening_law", "length",
    "radius", "bulk_viscosity", "fbar", "backend", "safety", "estimate_every",
    "sample_interval", "frame_interval", "friction", "bulk_viscosity_linear",
    "bulk_viscosity_quadratic",
}  # fmt: skip

#: What the Arlequin pair adds: the nested sizes and the coupling's options.
ARLEQUIN_INPUTS = {
    "coarse_radial", "coarse_axial", "ratio", "patch_rows", "band_rows", "coarse_size",
    "fine_size", "patch_length", "gluing_width", "weights", "mediator", "coupling",
    "coarse_step_ratio", "band_warning", "epsilon",
}  # fmt: skip


def _plain(value) -> bool:
    if isinstance(value, dict):
        return all(isinstance(k, str) and _plain(v) for k, v in value.items())
    if isinstance(value, list):
        return all(_plain(v) for v in value)
    return value is None or isinstance(value, (str, int, float, bool))


def test_recorded_inputs_are_plain_json(tmp_path):
    out = tmp_path / "run"
    run_taylor_bar(model="mono", elements_radial=3, t_end=0.5e-6, out=out, bulk_viscosity=True)
    inputs = json.loads((out / "results.json").read_text())["inputs"]
    assert set(inputs) == MONO_INPUTS
    assert all(_plain(q["value"]) for q in inputs.values())
    assert all(q["unit"] != "unspecified" for q in inputs.values())
    assert inputs["elements_radial"] == {"value": 3, "unit": "1"}
    assert inputs["mesh_size"]["unit"] == "m" and inputs["velocity"]["unit"] == "m/s"
    assert inputs["bulk_viscosity"]["value"] is True and inputs["fbar"]["value"] is True


def test_arlequin_inputs_record_objects_by_their_fields():
    # Python-only values (a weights object, a BulkViscosity) are recorded as named fields
    config = TaylorBarConfig(elements_radial=4, weights=RampWeights(epsilon=1e-3, edge=0.5),
                             bulk_viscosity=BulkViscosity(0.05, 1.2))  # fmt: skip
    _, _, record = build_bar(config, resolve(config))
    assert set(record) >= ARLEQUIN_INPUTS - {"epsilon"} | {"model", "geometry"}
    assert record["weights"] == {"type": "RampWeights", "epsilon": 1e-3, "edge": 0.5}
    assert all(_plain(v) for v in record.values())
    plain = config.inputs()
    assert plain["bulk_viscosity"] == {"linear": 0.05, "quadratic": 1.2}
    assert json.loads(json.dumps(plain)) == plain and set(plain) == set(config.units())


@pytest.mark.parametrize(
    ("argv", "kwargs", "match"),
    [
        (["--velocity", "-227"], {"velocity": -227.0}, "velocity must be positive"),
        (["--model", "mono", "--mediator", "coarse"], {"model": "mono", "mediator": "coarse"},
         r"\['mediator'\] apply to model='arlequin' only"),
        (["--elements-radial", "1"], {"elements_radial": 1}, "coarse cells cannot be larger"),
        (["--hardening-law", "voce", "--jc-n", "0.3"], {"hardening_law": "voce", "jc_n": 0.3},
         r"\['jc_n'\] do not belong to the voce law"),
        (["--geometry", "3d", "--model", "mono", "--elements-radial", "1"],
         {"geometry": "3d", "model": "mono", "elements_radial": 1}, "at least 2 cells"),
        (["--checkpoint-interval", "0"], {"checkpoint_interval": 0.0},
         "checkpoint_interval must be positive"),
    ],
)  # fmt: skip
def test_a_bad_value_is_the_same_error_everywhere(argv, kwargs, match, tmp_path, capsys):
    with pytest.raises(ValueError, match=match) as from_python:
        run_taylor_bar(out=tmp_path / "python", **kwargs)
    message = str(from_python.value)
    with pytest.raises(ValueError) as from_config:
        TaylorBarConfig(**kwargs)
    assert str(from_config.value) == message
    # the command line: exit status 2 and the same message, nothing written
    assert main(["taylor-bar", *argv, "--out", str(tmp_path / "cli"), "--quiet"]) == 2
    assert message in capsys.readouterr().err
    # a study's check of its cases, from the parsed options
    parser = demo_parser()[1]["taylor-bar"]
    with pytest.raises(ValueError) as from_study:
        check_case("taylor-bar", parser.parse_args(argv))
    assert str(from_study.value) == message
    assert not (tmp_path / "python").exists() and not (tmp_path / "cli").exists()


def test_the_progress_bar_counts_simulated_microseconds():
    assert TaylorBarConfig(t_end=40e-6).progress_scale() == (
        pytest.approx(40.0),
        "µs",
        1e6,
        "simulated time",
    )
