"""1D elastic wave through an Arlequin overlap: reflected and transmitted energy.

A smooth right-going pulse in a coarse bar (h = 1 cm, steel-like) meets a refined patch glued
at its left end (:mod:`.setup`); the reflection is measured against a single coarse-mesh run
with the same integrator and time step, the transmission as the α-weighted energy of the
patch's free zone, both as fractions of the incident energy (:mod:`.run`).

Modules: :mod:`.config` (``WaveConfig``, the ``arlequin wave`` options), :mod:`.setup`
(``wave_layout``), :mod:`.run` (``run_wave``), :mod:`.result` (``WaveResult``) and
:mod:`.report` (the results folder and ``plot_wave``).
"""

from ..config import register_runner
from . import run as _run
from .api import run_wave
from .config import INTEGRATORS, WaveConfig
from .report import plot_wave
from .result import WaveResult
from .setup import wave_layout

__all__ = ["INTEGRATORS", "WaveConfig", "WaveResult", "plot_wave", "run_wave", "wave_layout"]

# the configuration runs through its package's runner (it does not import its run module)
register_runner(WaveConfig, _run.run_config)
