"""The demos' subcommands, generated from their configurations (:mod:`arlequin.demos.config`).

Each field of a demo's configuration dataclass becomes one option of its subcommand: the flag
from the field name (``t_end`` -> ``--t-end``) unless the field says otherwise, the type from its
default, its choices, its mutually exclusive group, and a help text that ends with its unit and
default. The command itself makes the configuration from the parsed options (so the
configuration's checks run before any work), runs the demo under a progress bar, prints its
summary line and writes its JSON.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
from collections.abc import Callable, Iterator
from typing import Any

from ..demos.config import DemoConfig, Option
from ..io import close_running
from .common import add_out, progress_bar, write_json

__all__ = ["add_demo", "config_from_args", "parse_type", "run_command"]


def parse_type(field: dataclasses.Field, opt: Option) -> Callable[[str], Any] | None:
    """The converter of one command-line word for ``field`` (None: a string)."""
    if opt.parse is str:  # text: argparse's own (untyped) word
        return None
    if opt.parse is not None:
        return opt.parse
    default = field.default
    if isinstance(default, tuple) and default:
        default = default[0]
    if isinstance(default, bool) or isinstance(default, str):
        return None
    if isinstance(default, int):
        return int
    return float  # a float, or None: a number the demo computes when not given


def _help(field: dataclasses.Field, opt: Option) -> str:
    parts = [opt.help]
    if opt.unit not in ("", "1"):
        parts.append(f"[{opt.unit}]")
    text = " ".join(parts)
    if opt.default_help is not None:
        return f"{text} (default: {opt.default_help})"
    if isinstance(field.default, bool):
        return text
    return f"{text} (default: {field.default})" if field.default is not None else text


def add_demo(sub: Any, config: type[DemoConfig]) -> argparse.ArgumentParser:
    """Register ``config``'s subcommand on an ``add_subparsers`` object; returns its parser."""
    p = sub.add_parser(
        config.command,
        help=config.title,
        description=config.description,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    groups: dict[str, Any] = {}
    for field, opt in config.fields():
        if not opt.cli:
            continue
        target = p
        if opt.exclusive is not None:
            if opt.exclusive not in groups:
                groups[opt.exclusive] = p.add_mutually_exclusive_group()
            target = groups[opt.exclusive]
        flag = opt.flag or "--" + field.name.replace("_", "-")
        kwargs: dict[str, Any] = {"dest": field.name, "help": _help(field, opt)}
        if isinstance(field.default, bool):
            kwargs.update(action="store_false" if field.default else "store_true")
        else:
            kwargs.update(default=field.default, type=parse_type(field, opt))
            if opt.choices is not None:
                kwargs["choices"] = list(opt.choices)
            if opt.metavar is not None:
                kwargs["metavar"] = opt.metavar
            if opt.nargs is not None:
                kwargs["nargs"] = opt.nargs
        target.add_argument(flag, **kwargs)
    if "plot" in config.switches:
        p.add_argument("--plot", metavar="PNG", default=None, help="save a figure of the run")
    if "json" in config.switches:
        p.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON")
    if "quiet" in config.switches:
        p.add_argument("--quiet", action="store_true", help="no progress bar")
    if "resume" in config.switches:
        p.add_argument("--resume", action="store_true",
                       help="continue an interrupted run from the checkpoint in --out")  # fmt: skip
    if "out" in config.switches:
        add_out(p)
    p.set_defaults(func=lambda args: _main(config, args), config=config)
    return p


#: Options that may come with ``--resume`` (the inputs come from the checkpoint).
_RESUME_OPTIONS = {"out", "json", "quiet", "resume", "func", "command", "verbose", "config"}


def _main(config: type[DemoConfig], args: argparse.Namespace) -> int:
    if getattr(args, "resume", False):
        _resume(config, args)
        return 0
    made = config_from_args(config, args)
    result = run_command(made, args)
    if getattr(args, "plot", None):
        made.plot(result, args.plot)
    return 0


def _resume(config: type[DemoConfig], args: argparse.Namespace) -> Any:
    """``--resume --out DIR``: continue the run whose checkpoint is in DIR, with its inputs."""
    defaults = {f.name: f.default for f, _ in config.fields()}
    given = sorted(
        f"--{k.replace('_', '-')}"
        for k, v in vars(args).items()
        if k not in _RESUME_OPTIONS and k in defaults and v != defaults[k]
    )
    if given:
        raise ValueError(f"--resume continues with the inputs of the checkpoint; drop {given}")
    if args.out is None:
        raise ValueError("--resume needs --out DIR, the results folder of the interrupted run")
    total, unit, scale, label = config.resume_progress_scale(args.out)
    with progress_bar(total, unit, args.quiet, scale, label) as update, _ended(args.out):
        result = config.resume(args.out, progress=update)
    print(result.summary())
    write_json(args.json, result.to_json())
    return result


def config_from_args(config: type[DemoConfig], args: argparse.Namespace) -> DemoConfig:
    """The configuration of the parsed options (checked: a ``ValueError`` names a bad value)."""
    values = {f.name: getattr(args, f.name) for f, opt in config.fields() if opt.cli}
    values = {k: tuple(v) if isinstance(v, list) else v for k, v in values.items()}
    return config.from_mapping(values)


@contextlib.contextmanager
def _ended(out: str | None) -> Iterator[None]:
    """A run whose exception leaves ``out``'s results.json ``"failed"`` (``"interrupted"`` on
    Ctrl-C) with the exception's text, whatever raised it (see :func:`close_running`)."""
    try:
        yield
    except KeyboardInterrupt:
        close_running(out, "interrupted", "interrupted")
        raise
    except Exception as exc:
        close_running(out, "failed", f"{type(exc).__name__}: {exc}")
        raise


def run_command(config: DemoConfig, args: argparse.Namespace) -> Any:
    """Run a demo from its parsed options: under its progress bar (none with ``--quiet``), its
    summary line printed and its JSON written to ``--json``; returns the result."""
    total, unit, scale, label = config.progress_scale()
    out = getattr(args, "out", None)
    with progress_bar(total, unit, getattr(args, "quiet", False), scale, label) as update, \
            _ended(out):  # fmt: skip
        result = config.run(out=out, progress=update)
    print(result.summary())
    write_json(getattr(args, "json", None), result.to_json())
    return result
