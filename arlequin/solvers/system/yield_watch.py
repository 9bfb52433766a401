"""The gluing bands watched for plastic flow over a run (the coupling's, not the material's).

After each converged quasi-static step, or at each sample a dynamic run records, every J2
patch's gluing band is measured (the problem's ``band_plasticity``,
:func:`arlequin.coupling.band_plasticity.band_plasticity`):
the first time a band yields the run warns (:class:`~arlequin.contract.BandYieldWarning`, with
the load or time, the patch, the band's plastic share and the largest plastic strain there and
where), and the largest share over the run is kept for the result (``band_plastic_fraction``).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

from ...contract import BandYieldWarning

__all__ = ["UNWATCHED", "BandYieldWatch"]

#: The :attr:`BandYieldWatch.state` of a watch that has seen nothing (an older checkpoint's).
UNWATCHED: tuple[bool, tuple, bool] = (False, (), False)


class BandYieldWatch:
    """Plastic flow in the patches' gluing bands over a run.

    Parameters
    ----------
    problem_of : callable
        ``problem_of() -> problem``: the run's current problem (an adaptive run's grows); one
        with ``band_plasticity(states)`` (an :class:`~arlequin.ArlequinProblem`) is watched.
    when : str
        What the run's clock is in the warning: ``"λ"`` (a load factor) or ``"t"`` (s).
    deferred : bool
        Warn at :meth:`finish` rather than at the first plastic band: a dynamic adaptive run
        may reject the interval of a sample (:meth:`on_rewind` forgets it).

    Attributes
    ----------
    fraction : float or None
        Largest share of a band's quadrature weight that was plastic at a kept check (None
        before any check of a problem with a J2 patch).
    """

    def __init__(self, problem_of: Callable[[], Any], when: str = "λ",
                 deferred: bool = False) -> None:  # fmt: skip
        self.problem_of, self.when, self.deferred = problem_of, when, bool(deferred)
        self.watched = False
        #: (clock, band) of the checks that found a plastic band, in order
        self.plastic: list[tuple[float, Any]] = []
        self.warned = False

    @property
    def fraction(self) -> float | None:
        if not self.watched:
            return None
        return max((band.fraction for _, band in self.plastic), default=0.0)

    def __call__(self, solver: Any) -> None:
        """Measure the bands at the solver's committed ``states`` (at its ``t``)."""
        measure = getattr(self.problem_of(), "band_plasticity", None)
        if not callable(measure):
            return
        for band in measure(solver.states):
            self.watched = True
            if band.fraction > 0.0:
                self.plastic.append((float(solver.t), band))
        if not self.deferred:
            self._warn()

    @property
    def state(self) -> tuple[bool, list[tuple[float, Any]], bool]:
        """What the watch has seen (picklable), for a run's checkpoint: a resumed run reports
        the whole run's largest share and does not warn again."""
        return self.watched, list(self.plastic), self.warned

    @state.setter
    def state(self, value: tuple[bool, list[tuple[float, Any]], bool]) -> None:
        self.watched, self.plastic, self.warned = value[0], list(value[1]), value[2]

    def on_rewind(self, integ: Any) -> None:
        """A rejected interval: forget the checks after the integrator's time."""
        self.plastic = [(t, band) for t, band in self.plastic if t <= float(integ.t)]

    def _warn(self) -> None:
        if self.warned or not self.plastic:
            return
        self.warned = True
        t, band = self.plastic[0]
        x = ", ".join(f"{c:.4g}" for c in band.position)
        warnings.warn(
            f"at {self.when} = {t:.6g} {band.patch} yields in its gluing band "
            f"({band.fraction:.3g} of the band plastic, largest plastic strain {band.peak:.3g} "
            f"at x = ({x}) m): the band's fields are the coupling's, not the material's (widen "
            "the patch so that its plastic zone stays inside the band's inner edge, or use "
            "mediator='fine', exact on a nested patch)",
            BandYieldWarning,
            stacklevel=4,
        )

    def finish(self, result: Any) -> Any:
        """``result`` with ``band_plastic_fraction`` (the largest share kept, None if nothing
        was watched); a deferred watch warns here."""
        self._warn()
        result.band_plastic_fraction = self.fraction
        return result
