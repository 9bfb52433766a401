"""The study file of :mod:`arlequin.demos.study`: its parsing into cases and the checks made
before any case runs (the demo, each option, each value through the command's own parser, and
the demo's own input checks)."""

from __future__ import annotations

import hashlib
import importlib
import itertools
import json
import os
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["DEMOS", "Case", "StudyError", "StudySpec", "load_spec"]

#: The CLI demos a study can run: every subcommand of ``arlequin`` registered by
#: :func:`arlequin.cli.demos.add_demos` (read once, when first needed).
DEMOS: tuple[str, ...] = ()


def _demos() -> tuple[str, ...]:
    global DEMOS
    if not DEMOS:
        from ...cli.demos import demo_parser

        DEMOS = tuple(demo_parser()[1])
    return DEMOS


class StudyError(ValueError):
    """A study file that cannot run: the key and the value at fault are named."""


@dataclass(frozen=True)
class Case:
    """One case of a study: its number, a stable id and its parameters (CLI option names)."""

    number: int
    params: dict[str, Any]

    @property
    def case_id(self) -> str:
        """``case-NNNN-<hash>``: the number and a digest of the parameters (stable across runs
        of the same study file)."""
        digest = hashlib.blake2b(json.dumps(self.params, sort_keys=True).encode(),
                                 digest_size=4).hexdigest()  # fmt: skip
        return f"case-{self.number:04d}-{digest}"


@dataclass
class StudySpec:
    """A parsed study file: the demo and its cases."""

    demo: str
    cases: list[Case]
    source: dict[str, Any] = field(default_factory=dict)


def _subparser(demo: str):
    from ...cli.demos import demo_parser

    return demo_parser()[1][demo]


def _cli_value(value: Any) -> list[str]:
    if isinstance(value, bool):
        return []
    if isinstance(value, (list, tuple)):
        return [str(v) for v in value]
    return [str(value)]


def _argv(demo: str, params: Mapping[str, Any], parser) -> list[str]:
    """The command line of a case (``--json`` and ``--out`` added by the runner)."""
    argv = [demo]
    opts = {a.dest: a for a in parser._actions}
    for key, value in params.items():
        action = opts[key]
        flag = max(action.option_strings, key=len)
        if isinstance(value, bool):
            if value != bool(action.default):
                argv.append(flag)
            continue
        argv += [flag, *_cli_value(value)]
    return argv


def _check_case(demo: str, params: Mapping[str, Any], parser) -> None:
    opts = {a.dest: a for a in parser._actions if a.option_strings}
    for key, value in params.items():
        if key in ("json", "out", "quiet", "help", "resume"):
            raise StudyError(f"parameter {key!r} is set by the study itself")
        if key not in opts:
            _unknown_option(demo, key, opts)
        action = opts[key]
        if isinstance(value, bool) != (action.nargs == 0):
            kind = "true or false" if action.nargs == 0 else "a value"
            raise StudyError(f"parameter {key!r} of {demo!r} takes {kind}, got {value!r}")
        if isinstance(value, bool):
            continue
        if (
            isinstance(action.nargs, int)
            and action.nargs > 1
            and not (isinstance(value, (list, tuple)) and len(value) == action.nargs)
        ):
            raise StudyError(f"parameter {key!r} of {demo!r} takes {action.nargs} values "
                             f"(a list of {action.nargs}), got {value!r}")  # fmt: skip
        values = value if isinstance(value, (list, tuple)) else [value]
        for v in values:
            _check_value(demo, key, v, action)
    _check_ranges(demo, params, parser)


def _unknown_option(demo: str, key: str, opts: Mapping[str, Any]) -> None:
    """Raise the :class:`StudyError` of a parameter ``key`` that is no option of ``demo``,
    with the closest option's name as a hint."""
    import difflib

    known = sorted(k for k in opts if k not in ("json", "out", "quiet", "help"))
    close = difflib.get_close_matches(key, known, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise StudyError(f"parameter {key!r} is not an option of {demo!r}{hint} "
                     f"(options: {known})")  # fmt: skip


def _check_value(demo: str, key: str, v: Any, action) -> None:
    """One value ``v`` of the parameter ``key``: converted by the option's type, a number
    given as a number, one of the option's choices."""
    try:
        converted = action.type(str(v)) if action.type is not None else str(v)
    except (TypeError, ValueError) as exc:
        kind = getattr(action.type, "__name__", "value")
        raise StudyError(f"parameter {key!r} of {demo!r}: {v!r} is not a valid "
                         f"{kind}") from exc  # fmt: skip
    if isinstance(v, str) and action.type in (int, float):
        raise StudyError(f"parameter {key!r} of {demo!r}: {v!r} is text, not a number")
    if action.choices is not None and converted not in action.choices:
        raise StudyError(f"parameter {key!r} of {demo!r}: {v!r} is not one of "
                         f"{list(action.choices)}")  # fmt: skip


def _check_ranges(demo: str, params: Mapping[str, Any], parser) -> None:
    """The demo's own input checks on the case's parsed command line (before any case runs)."""
    from ...cli.demos import check_case

    args = parser.parse_args(_argv(demo, params, parser)[1:])
    try:
        check_case(demo, args)
    except ValueError as exc:
        raise StudyError(f"{demo}: {exc} (parameters {dict(params)})") from exc


def load_spec(spec: str | os.PathLike | Mapping[str, Any]) -> StudySpec:
    """Parse and check a study (a TOML file, or its mapping); see the module docstring.

    Raises
    ------
    StudyError
        An unknown demo, an unknown parameter, a value of the wrong type or out of range (the
        key named), an empty study.
    """
    data = _read_spec(spec)
    unknown = sorted(set(data) - {"demo", "parameters", "cases"})
    if unknown:
        raise StudyError(f"unknown keys {unknown} in the study (keys: demo, parameters, cases)")
    demo = data.get("demo")
    if not isinstance(demo, str):
        raise StudyError(f'the study needs demo = "<name>" (one of {list(_demos())}), got {demo!r}')
    cases = [Case(i, c) for i, c in enumerate(_combinations(data))]
    if ":" in demo:
        _resolve(demo)  # importable
    elif demo not in _demos():
        raise StudyError(f'demo {demo!r} is not one of {list(_demos())} (or "module:function")')
    else:
        parser = _subparser(demo)
        for case in cases:
            _check_case(demo, case.params, parser)
    ids = [c.case_id for c in cases]
    if len(set(ids)) != len(ids):
        raise StudyError("the study has the same case twice")
    return StudySpec(demo, cases, data)


def _read_spec(spec: str | os.PathLike | Mapping[str, Any]) -> dict[str, Any]:
    """The study as a dictionary: the mapping given, or the TOML file read."""
    if isinstance(spec, Mapping):
        return dict(spec)
    path = Path(spec)
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise StudyError(f"cannot read the study file {str(path)!r}: {exc}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"study file {str(path)!r} is not valid TOML: {exc}") from exc


def _combinations(data: Mapping[str, Any]) -> list[dict[str, Any]]:
    """The parameters of each case: the grid of the ``[parameters]`` given as lists (the
    others fixed), then each of the ``[[cases]]`` over the fixed ones."""
    params = dict(data.get("parameters", {}))
    if not isinstance(params, dict):
        raise StudyError("[parameters] must be a table of option = value or [values]")
    axes = {k: v for k, v in params.items() if isinstance(v, list) and not _is_pair(k, v)}
    fixed = {k: v for k, v in params.items() if k not in axes}
    for k, v in axes.items():
        if not v:
            raise StudyError(f"parameter {k!r} has an empty list of values")
    explicit = data.get("cases", [])
    if not isinstance(explicit, list) or not all(isinstance(c, dict) for c in explicit):
        raise StudyError("[[cases]] must be a list of tables")
    combos: list[dict[str, Any]] = []
    if axes or not explicit:
        keys = list(axes)
        for values in itertools.product(*(axes[k] for k in keys)):
            combos.append({**fixed, **dict(zip(keys, values))})
    combos += [{**fixed, **c} for c in explicit]
    return combos


def _is_pair(key: str, value: list) -> bool:
    """Options that take several values (``lengths = [1.0, 2.0]``) are not grid axes unless
    given as a list of lists."""
    return key == "lengths" and not any(isinstance(v, list) for v in value)


def _resolve(target: str) -> Callable[..., Mapping[str, Any]]:
    module, _, name = target.partition(":")
    try:
        return getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as exc:
        raise StudyError(f"demo {target!r}: cannot import {name!r} from {module!r}: {exc}") from exc
