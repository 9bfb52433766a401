"""The patch test's Python entry points (their signatures kept): each builds the checked
:class:`PatchTestConfig` from its keyword arguments, then builds or runs it."""

from __future__ import annotations

from pathlib import Path

from .config import PatchTestConfig
from .result import PatchTestResult
from .run import run_config
from .setup import build_problem

__all__ = ["build_patch_test_problem", "run_patch_test"]


def run_patch_test(
    dim: str | int = "2",
    coupling: str = "H1",
    weights: str = "ramp",
    mediator: str = "coarse",
    mesh: str = "nested",
    seed: int = 0,
    out: str | Path | None = None,
    layout: str = "random",
    ratio: int = 4,
    band_cells: int = 1,
) -> PatchTestResult:
    """Run one random patch test; see :mod:`arlequin.demos.patch_test`.

    Parameters
    ----------
    dim : {"1", "2", "3", "axi"}
    coupling : {"L2", "H1"}
    weights : {"constant", "ramp"}
    mediator : {"coarse", "fine"}
    mesh : {"nested", "nonnested"}
    seed : int
        Seed of the random layout (≥ 0).
    out : path, optional
        Results folder to write (:class:`arlequin.io.ResultsFolder`): results.json,
        history.csv (the strain energies and the residual) and one frame per model (the
        displacement, the weight alpha, the multiplier field).
    layout : {"random", "strip", "square"}
        ``"random"``: the random configuration; ``"strip"``: a uniform 2D grid with a patch
        spanning it from bottom to top (touching the coarse boundary), glued at its two ends;
        ``"square"``: a square patch inside the grid, glued all around (its band turns
        corners: not an exact configuration with the coarse mediator). 2D only.
    ratio : int
        Coarse/fine cell size ratio of the strip and square layouts.
    band_cells : int
        Gluing band width in coarse cells (strip and square layouts).
    """
    config = PatchTestConfig(dim=dim, coupling=coupling, weights=weights, mediator=mediator,
                             mesh=mesh, seed=seed, layout=layout, ratio=ratio,
                             band_cells=band_cells)  # fmt: skip
    return run_config(config, out)


def build_patch_test_problem(
    dim: str | int = "2",
    coupling: str = "H1",
    weights: str = "ramp",
    mediator: str = "coarse",
    mesh: str = "nested",
    seed: int = 0,
    layout: str = "random",
    ratio: int = 4,
    band_cells: int = 1,
):
    """Build the patch-test problem (see :func:`~arlequin.demos.patch_test.run_patch_test`).

    Returns
    -------
    problem : ArlequinProblem
        With tractions and rigid-motion supports applied.
    exact : callable
        The exact displacement u(x) = A x, x of shape (dim, ...) (m).
    """
    config = PatchTestConfig(dim=dim, coupling=coupling, weights=weights, mediator=mediator,
                             mesh=mesh, seed=seed, layout=layout, ratio=ratio,
                             band_cells=band_cells)  # fmt: skip
    return build_problem(config)
