"""Demo configurations: one frozen dataclass a demo, the single source of its parameters.

A demo's configuration (a subclass of :class:`DemoConfig`) declares each parameter once, as a
dataclass field made by :func:`option`: its default, its unit (SI), its help text and, where the
command line needs them, its flag, choices or mutually exclusive group. From it come

* the demo's subcommand of ``arlequin`` (:mod:`arlequin.cli.generate`): one option a field,
  its ``--help`` with the unit and the default;
* the keys of a parameter study (:mod:`arlequin.demos.study`): the field names, each value
  parsed as the command line would parse it;
* the inputs recorded in ``results.json`` (:meth:`DemoConfig.inputs` and
  :meth:`DemoConfig.units`): plain JSON, a material an object with named fields.

Its ``check`` method validates the inputs when the configuration is made, so a bad value is a
``ValueError`` naming the quantity and its value before any work, whether the configuration
comes from the command line, a study file or Python.

A configuration runs through the runner its demo's package registers (:func:`register_runner`,
in the package's ``__init__.py``): the configuration never imports its own run module, which
imports it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

__all__ = [
    "DemoConfig",
    "Option",
    "Runner",
    "check_choice",
    "check_positive",
    "check_range",
    "option",
    "register_runner",
    "runner_of",
]


@dataclass(frozen=True)
class Option:
    """How one configuration field is shown on the command line.

    Parameters
    ----------
    help : str
        What the parameter is (the unit and the default are added to the ``--help`` text).
    unit : str
        Its SI unit (``"1"`` dimensionless, ``""`` for names and choices).
    flag : str, optional
        The command-line flag; default ``--`` and the field name with ``-`` for ``_``.
    metavar : str, optional
    choices : tuple, optional
        The values allowed (the command line refuses others).
    exclusive : str, optional
        The name of a group of mutually exclusive options (at most one given).
    nargs : int, optional
        Number of values the option takes (a tuple-valued field).
    parse : callable, optional
        Converts one command-line word to a value; default from the field's default (``int``,
        ``float`` or ``str``; for a ``None`` default, ``float``).
    cli : bool
        False for parameters given from Python only (not on the command line).
    default_help : str, optional
        How ``--help`` shows the default when it is ``None`` (computed by the demo).
    """

    help: str
    unit: str = "1"
    flag: str | None = None
    metavar: str | None = None
    choices: tuple | None = None
    exclusive: str | None = None
    nargs: int | None = None
    parse: Callable[[str], Any] | None = None
    cli: bool = True
    default_help: str | None = None


def option(default: Any, help: str, unit: str = "1", **kwargs: Any) -> Any:
    """A configuration field: ``default`` and its :class:`Option` (``help``, ``unit``, ...).

    A mutable default (a list, a dict) is refused: use a tuple.
    """
    if isinstance(default, (list, dict, set)):
        raise TypeError(f"option default {default!r}: use an immutable value (a tuple)")
    return dataclasses.field(default=default, metadata={"option": Option(help, unit, **kwargs)})


@dataclass(frozen=True)
class DemoConfig:
    """The base of the demos' configurations (frozen dataclasses of :func:`option` fields).

    Class attributes
    ----------------
    command : str
        The subcommand of ``arlequin`` (``"sliding-block"``).
    title : str
        One line for ``arlequin --help``.
    description : str
        The subcommand's ``--help`` paragraph.
    switches : tuple of str
        The run controls the subcommand takes besides the parameters: ``"json"`` (write the
        results as JSON), ``"out"`` (a results folder), ``"quiet"`` (no progress bar), and,
        for some demos, ``"plot"`` and ``"resume"``.
    """

    command: ClassVar[str] = ""
    title: ClassVar[str] = ""
    description: ClassVar[str] = ""
    switches: ClassVar[tuple[str, ...]] = ("json", "quiet", "out")

    def __post_init__(self) -> None:
        self.check()

    def check(self) -> None:
        """Validate the inputs (``ValueError`` naming the quantity and its value)."""

    # -- the fields -------------------------------------------------------------------------
    @classmethod
    def fields(cls) -> Iterator[tuple[dataclasses.Field, Option]]:
        """The configuration's fields and their :class:`Option`, in declaration order."""
        for f in dataclasses.fields(cls):
            yield f, f.metadata.get("option") or Option(help=f.name)

    @classmethod
    def units(cls) -> dict[str, str]:
        """The SI unit of each field, by name (recorded in ``results.json``)."""
        return {f.name: opt.unit for f, opt in cls.fields()}

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]) -> DemoConfig:
        """A configuration from a mapping of field names (unknown names refused, by name)."""
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(
                f"{cls.command or cls.__name__}: unknown parameters {unknown} (parameters: "
                f"{sorted(known)})"
            )
        return cls(**values)

    def inputs(self) -> dict[str, Any]:
        """The parameters as plain JSON (numbers, strings, lists; dataclass values such as a
        material as objects of their named fields)."""
        return {f.name: _plain(getattr(self, f.name)) for f, _ in self.fields()}

    # -- running -----------------------------------------------------------------------------
    def run(self, out: str | None = None, progress: Callable[[float], None] | None = None) -> Any:
        """Run the demo (``out``: a results folder; ``progress``: called with the progress in
        the unit of :meth:`progress_scale`); returns its result (``summary()``,
        ``to_json()``). Runs the ``run`` of the runner registered for the configuration's
        class (:func:`register_runner`); a demo in one module may override this method."""
        runner = runner_of(type(self))
        if runner is None:
            raise NotImplementedError(f"{type(self).__name__}.run")
        return runner.run(self, out=out, progress=progress)

    def progress_scale(self) -> tuple[float, str, float, str]:
        """The progress bar: ``(total, unit, scale, label)``; ``run`` reports ``x`` shown as
        ``x * scale`` of ``total`` (default: the fraction done, shown in percent)."""
        return 100.0, "%", 100.0, self.command

    def plot(self, result: Any, path: str) -> None:
        """Save a figure of ``result`` to ``path`` (the demos with a ``--plot`` switch)."""
        raise NotImplementedError(f"{type(self).__name__}.plot")

    @classmethod
    def resume(cls, out: str, progress: Callable[[float], None] | None = None) -> Any:
        """Continue the interrupted run whose checkpoint is in ``out`` (the demos with a
        ``--resume`` switch): the ``resume`` of the registered runner."""
        runner = runner_of(cls)
        if runner is None or runner.resume is None:
            raise NotImplementedError(f"{cls.__name__}.resume")
        return runner.resume(out, progress=progress)

    @classmethod
    def resume_progress_scale(cls, out: str) -> tuple[float, str, float, str]:
        """The progress bar of :meth:`resume`."""
        return 100.0, "%", 100.0, cls.command

    def replace(self, **changes: Any) -> DemoConfig:
        """A copy with some parameters changed (checked again)."""
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
class Runner:
    """How a demo's configuration runs: ``run(config, out=, progress=)`` returning its result
    and, for the demos with ``--resume``, ``resume(out, progress=)``."""

    run: Callable[..., Any]
    resume: Callable[..., Any] | None = None


#: Configuration class -> its runner, filled by the demos' packages (:func:`register_runner`).
RUNNERS: dict[type, Runner] = {}


def register_runner(
    config: type[DemoConfig], run: Callable[..., Any], resume: Callable[..., Any] | None = None
) -> None:
    """Register how the configurations of class ``config`` run (:class:`Runner`): called by
    the demo's package (its ``__init__.py``, which imports both the configuration and the run
    module), so that :meth:`DemoConfig.run` and :meth:`DemoConfig.resume` reach the run module
    without the configuration importing it."""
    RUNNERS[config] = Runner(run, resume)


def runner_of(config: type[DemoConfig]) -> Runner | None:
    """The runner registered for ``config`` or, failing that, for the nearest of its bases
    (None if none)."""
    for cls in config.__mro__:
        runner = RUNNERS.get(cls)
        if runner is not None:
            return runner
    return None


def _plain(value: Any) -> Any:
    """``value`` as plain JSON: dataclasses as objects of their fields, tuples as lists."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, (tuple, list)):
        return [_plain(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    return value


# -- checks shared by the configurations ----------------------------------------------------
def check_positive(name: str, value: float | None, unit: str = "", *, allow_none: bool = False,
                   allow_zero: bool = False) -> None:  # fmt: skip
    """Refuse a value that is not a finite positive number (or non-negative with
    ``allow_zero``); ``None`` passes with ``allow_none``."""
    if value is None and allow_none:
        return
    ok = isinstance(value, (int, float)) and math.isfinite(value)
    ok = ok and (value >= 0.0 if allow_zero else value > 0.0)
    if not ok:
        what = "non-negative" if allow_zero else "positive"
        suffix = f" ({unit})" if unit else ""
        raise ValueError(f"{name} must be a {what} finite number{suffix}, got {name}={value!r}")


def check_range(name: str, value: float, low: float, high: float, *, closed: str = "[)") -> None:
    """Refuse a value outside the interval from ``low`` to ``high`` (``closed`` says which ends
    belong to it: ``"[)"``, ``"()"``, ``"[]"`` or ``"(]"``)."""
    ok = isinstance(value, (int, float)) and math.isfinite(value)
    if ok:
        ok = (value >= low if closed[0] == "[" else value > low) and (
            value <= high if closed[1] == "]" else value < high
        )
    if not ok:
        raise ValueError(
            f"{name} must lie in {closed[0]}{low}, {high}{closed[1]}, got {name}={value!r}"
        )


def check_choice(name: str, value: Any, choices: tuple) -> None:
    """Refuse a value that is not one of ``choices``."""
    if value not in choices:
        raise ValueError(f"{name} must be one of {list(choices)}, got {name}={value!r}")
