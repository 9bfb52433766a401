"""Every subcommand's options and defaults, against the record taken before the CLI was
generated from the demos' configurations (``tests/data/cli_options.json``, written from the
hand-written parsers of commit 826bb02 by describing each argparse action), and against the
configuration dataclass it is generated from."""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

import pytest

from arlequin.cli.main import build_parser

RECORD = json.loads((Path(__file__).parent / "data" / "cli_options.json").read_text())


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    root = build_parser()
    sub = next(a for a in root._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def _describe(parser: argparse.ArgumentParser) -> dict[str, dict]:
    groups = {}
    for g in parser._mutually_exclusive_groups:
        names = sorted(a.dest for a in g._group_actions)
        for a in g._group_actions:
            groups[a.dest] = names
    out = {}
    for a in parser._actions:
        if isinstance(a, argparse._HelpAction):
            continue
        default = list(a.default) if isinstance(a.default, tuple) else a.default
        out[a.dest] = {
            "flags": list(a.option_strings),
            "default": default,
            "type": getattr(a.type, "__name__", None) if a.type else None,
            "choices": list(a.choices) if a.choices is not None else None,
            "nargs": a.nargs,
            "required": a.required,
            "exclusive_with": groups.get(a.dest),
        }
    return out


@pytest.mark.parametrize("command", sorted(RECORD))
def test_options_and_defaults_unchanged(command):
    """Each recorded option keeps its flags, default, type, choices, nargs and group (options
    may be added)."""
    now = _describe(_subparsers()[command])
    for dest, was in RECORD[command].items():
        assert dest in now, f"{command}: option {was['flags']} is gone"
        got = now[dest]
        for key in ("default", "type", "choices", "nargs", "required", "exclusive_with"):
            assert got[key] == was[key], (command, dest, key, got[key], was[key])
        assert set(was["flags"]) <= set(got["flags"]), (command, dest, got["flags"])


def test_generated_subcommands_follow_their_configuration():
    """A generated subcommand has one option per command-line field of its configuration, with
    the field's default, and nothing else but its run switches."""
    checked = 0
    for name, parser in _subparsers().items():
        config = parser.get_default("config")
        if config is None:
            continue
        checked += 1
        assert config.command == name
        now = _describe(parser)
        fields = {f.name: f for f, opt in config.fields() if opt.cli}
        assert set(now) - set(fields) <= set(config.switches), (name, set(now) - set(fields))
        for field_name, f in fields.items():
            default = list(f.default) if isinstance(f.default, tuple) else f.default
            assert now[field_name]["default"] == default, (name, field_name)
            assert dataclasses.is_dataclass(config)
    assert checked >= 1
