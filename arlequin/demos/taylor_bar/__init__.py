"""The Taylor bar impact demo (``arlequin taylor-bar``): a copper bar hits a rigid wall.

Modules: :mod:`.config` (:class:`TaylorBarConfig`, the parameters), :mod:`.setup` (the inputs
resolved and checked, the bar built), :mod:`.meshes`, :mod:`.meshes_3d` and :mod:`.graded_3d`
(the meshes), :mod:`.models` and :mod:`.models_3d` (one mesh or the Arlequin pair, axisymmetric
or a 3D quarter), :mod:`.record` (the history, the balance, the field frames), :mod:`.checkpoint`
(checkpoints and resuming), :mod:`.run` (the run as named steps), :mod:`.result`
(:class:`TaylorBarResult`, the JSON keys, the units), :mod:`.report`, :mod:`.render` and
:mod:`.render_3d` (the results written, the pictures), :mod:`.api` (:func:`run_taylor_bar`,
:func:`resume_taylor_bar`).
"""

from ..config import register_runner
from . import run as _run
from .api import resume_taylor_bar, run_taylor_bar
from .config import TaylorBarConfig
from .meshes import taylor_bar_mesh
from .models import hardening_parameters
from .record import HISTORY_UNITS
from .result import (
    ARLEQUIN_JSON_KEYS,
    JSON_KEYS,
    MODELS,
    TAYLOR_REFERENCE,
    GluingBandPlasticityWarning,
    TaylorBarResult,
)

__all__ = [
    "ARLEQUIN_JSON_KEYS",
    "HISTORY_UNITS",
    "JSON_KEYS",
    "MODELS",
    "TAYLOR_REFERENCE",
    "GluingBandPlasticityWarning",
    "TaylorBarConfig",
    "TaylorBarResult",
    "hardening_parameters",
    "resume_taylor_bar",
    "run_taylor_bar",
    "taylor_bar_mesh",
]

# the configuration runs through its package's runner (it does not import its run module)
register_runner(TaylorBarConfig, _run.run_config, resume=_run.resume_run)
