"""The patch test's run: build, solve, compare with the exact fields (see
:mod:`arlequin.demos.patch_test`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...io import ResultsFolder
from ...solvers.statics.static import solve_static
from .report import write_folder
from .result import PatchTestResult
from .setup import build_problem, nodal

if TYPE_CHECKING:
    from .config import PatchTestConfig

__all__ = ["run_config"]


def run_config(config: PatchTestConfig, out: str | Path | None = None) -> PatchTestResult:
    """Run the patch test of ``config`` (results folder in ``out`` if given)."""
    problem, exact = build_problem(config)
    inputs = config.inputs()
    folder = None
    if out is not None:
        folder = ResultsFolder(out, "arlequin patch-test", inputs, config.units())
    coarse_mesh = problem.coarse.mesh
    fine_mesh = problem.patches[0].model.mesh
    result = solve_static(problem)
    name = problem.block_names[1]
    u_exact = {"coarse": nodal(exact, coarse_mesh), name: nodal(exact, fine_mesh)}
    scale = max(np.abs(v).max() for v in u_exact.values())
    max_error = max(np.abs(result.displacements[k] - v).max() for k, v in u_exact.items()) / scale
    sp_sys = result.saddle_point
    u_full = np.concatenate([u_exact["coarse"], u_exact[name]])
    solved = np.concatenate([result.multipliers[k] for k in sp_sys.multiplier_slices])
    lam = sp_sys.best_multipliers(u_full, initial=solved)
    residual = sp_sys.residual(u_full, lam)
    pc = problem.couplings[0]
    out_result = PatchTestResult(
        max_error=float(max_error),
        exact_residual=float(residual),
        n_coarse_dofs=int(problem.coarse.n_dofs),
        n_fine_dofs=int(problem.patches[0].model.n_dofs),
        n_multipliers=int(pc.coupling.n_multipliers),
        dim=config.dim,
        coupling=config.coupling,
        weights=config.weights,
        mediator=config.mediator,
        mesh=config.mesh,
        seed=int(config.seed),
        overlap_method=pc.overlap.method,
        exact_expected=not pc.exactness_failures,
    )
    out_result.static = result
    if folder is not None:
        meshes = {"coarse": coarse_mesh, name: fine_mesh}
        write_folder(folder, problem, out_result, meshes, u_exact, scale, set(inputs))
    return out_result
