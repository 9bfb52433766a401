"""Cost of building a patch's coupling (overlap, weights, coupling matrices) vs stiffness assembly.

Patches of structured coarse meshes of the unit square / cube, nested
(:func:`arlequin.coupling.patches.refine_region` of the middle box [0.25, 0.75]^d) or not; gluing
band one
coarse cell wide:

``2d``         56 × 56 squares split into triangles (6272 cells), the patch refined 3 times:
               100 352 fine triangles (the target size).
``3d``         16³ cubes split into 6 tetrahedra (24 576 cells), the patch refined twice:
               196 608 fine tetrahedra (the target size).
``3d_small``   as ``3d`` refined once: 24 576 fine tetrahedra (scaling).
``3d_medium``  24³ cubes (82 944 tetrahedra), the patch refined once: 82 944 fine tetrahedra.
``3d_nonnested``  the coarse mesh of ``3d``, the patch a mesh of its own: the box
               [0.27, 0.73] × [0.26, 0.745] × [0.255, 0.76] (its faces cut coarse cells), 32³
               cubes split into 6 tetrahedra: 196 608 fine tetrahedra, none nested (the target
               size); ``3d_nonnested_small``: 16³ cubes, 24 576 tetrahedra.

For each, in one process:

* ``coupling``: ``ArlequinProblem(coarse, [Patch(fine, ...)]).couplings`` — builds the overlap,
  classifies the patch boundary, selects the gluing zone, evaluates the partition weights and
  assembles the coupling matrices (H1, coarse mediator, ramp weights). Phases are timed by
  wrapping (at run time, without editing the library) ``arlequin.coupling.gluing.build_overlap``,
  ``PatchCoupling._classify_boundary``, ``PatchCoupling._fine_gluing_zone``,
  ``PatchCoupling._evaluate_weights`` and ``arlequin.coupling.gluing.coupling_matrices``; ``other``
  is the rest of the constructor (mainly the integration model's basis).
* ``skfem``: scikit-fem's own linear-elasticity assembly of the fine stiffness on the patch mesh
  (``Basis`` construction + ``asm(linear_elasticity)``), at scikit-fem's default quadrature and
  at the model's quadrature order (3, also used by the coupling);
* ``model``: ``LinearElastic(fine_mesh, ...)`` construction + ``.stiffness()``.

Wall times (s) are the best of ``--repeat`` runs (``time.perf_counter``); peak memory (bytes) is
the ``tracemalloc`` peak of a separate run of each step (tracemalloc slows Python code down, so it
is never on during the timed runs); ``maxrss`` is the process's peak resident set size (bytes,
``resource.getrusage``), and each case runs in its own subprocess so that it is per case;
``coupling_alone_maxrss_bytes`` is the peak of a child process that builds the meshes and the
coupling only. The
ratios are coupling time / assembly time and coupling peak / assembly peak; the target is ≤ 2
for nested patches and ≤ 4 for non-nested ones (``within_target`` compares with scikit-fem's
assembly at its default quadrature), and a peak resident memory ≤ 3 GB. A coupling
build that runs out of memory is reported as ``coupling_error`` with the phase times so far.

Usage: ``python benchmarks/coupling_assembly.py [--case NAME|all] [--repeat 3] [--profile]
[--mem-limit-gb 16] [--timeout 1800]``. Prints one JSON object. With ``all`` each case runs in a
child process under an address-space limit and a timeout; a case that fails is reported with its
error instead of results. ``--profile`` adds the top cProfile entries (cumulative and internal
time) of one coupling build per case.
"""

from __future__ import annotations

import argparse
import cProfile
import gc
import io
import json
import platform
import pstats
import resource
import subprocess
import sys
import time
import tracemalloc
from collections import defaultdict
from collections.abc import Callable

import numpy as np
import scipy
import shapely  # noqa: F401  (imported lazily by the library: keep import time out of timings)
import skfem
import trimesh  # noqa: F401
from skfem import Basis, ElementTetP1, ElementTriP1, ElementVector, MeshTet, MeshTri, asm
from skfem.models.elasticity import lame_parameters, linear_elasticity

import arlequin.coupling.gluing as problem_module
from arlequin.coupling.patches import refine_region
from arlequin.models import IsotropicElastic, LinearElastic
from arlequin.problem.arlequin_problem import ArlequinProblem, Patch, PatchCoupling

YOUNG, POISSON = 200e9, 0.3  # steel (Pa, -)

_BOX2 = ((0.25, 0.25), (0.75, 0.75))
_BOX3 = ((0.25, 0.25, 0.25), (0.75, 0.75, 0.75))
_BOX3_OFF = ((0.27, 0.26, 0.255), (0.73, 0.745, 0.76))  # faces cutting coarse cells
CASES = {
    # n: coarse cells per side of the unit square / cube; box: patch region; levels: refinement
    "2d": {"n": 56, "box": _BOX2, "levels": 3},  # 100 352 fine triangles (the target size)
    "3d": {"n": 16, "box": _BOX3, "levels": 2},  # 196 608 fine tetrahedra (the target size)
    "3d_small": {"n": 16, "box": _BOX3, "levels": 1},  # 24 576 fine tetrahedra (scaling)
    "3d_medium": {"n": 24, "box": _BOX3, "levels": 1},  # 82 944 fine tetrahedra (scaling)
    # non-nested: the patch its own structured mesh of a box off the coarse planes, n_fine
    # cubes a side split into 6 tetrahedra
    "3d_nonnested_small": {"n": 16, "box": _BOX3_OFF, "n_fine": 16},  # 24 576 fine tetrahedra
    "3d_nonnested": {"n": 16, "box": _BOX3_OFF, "n_fine": 32},  # 196 608 (the target size)
}
DEFAULT_CASES = ("2d", "3d_small", "3d_medium", "3d", "3d_nonnested_small", "3d_nonnested")


def build_meshes(case: str) -> tuple[skfem.Mesh, skfem.Mesh, float]:
    """Coarse mesh, nested patch mesh and gluing width (m, one coarse cell) of a case."""
    cfg = CASES[case]
    x = np.linspace(0.0, 1.0, cfg["n"] + 1)
    coarse = MeshTri.init_tensor(x, x) if len(cfg["box"][0]) == 2 else MeshTet.init_tensor(x, x, x)
    if "n_fine" in cfg:  # non-nested
        lo, hi = cfg["box"]
        axes = [np.linspace(a, b, cfg["n_fine"] + 1) for a, b in zip(lo, hi)]
        return coarse, MeshTet.init_tensor(*axes), 1.0 / cfg["n"]
    fine = refine_region(coarse, levels=cfg["levels"], box=cfg["box"])
    return coarse, fine, 1.0 / cfg["n"]


class PhaseTimer:
    """Wrap library callables at run time to accumulate their wall time per phase."""

    def __init__(self) -> None:
        self.times: dict[str, float] = defaultdict(float)
        self._undo: list[tuple[object, str, object]] = []

    def wrap(self, owner: object, name: str, phase: str) -> None:
        original = getattr(owner, name, None)
        if original is None:  # the library changed: report the phase as missing, keep going
            return
        times = self.times

        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                times[phase] += time.perf_counter() - t0

        setattr(owner, name, timed)
        self._undo.append((owner, name, original))

    def __enter__(self) -> PhaseTimer:
        self.wrap(problem_module, "build_overlap", "overlap")
        self.wrap(PatchCoupling, "_classify_boundary", "boundary")
        self.wrap(PatchCoupling, "_fine_gluing_zone", "gluing_zone")
        self.wrap(PatchCoupling, "_evaluate_weights", "weights")
        self.wrap(problem_module, "coupling_matrices", "coupling_matrices")
        return self

    def __exit__(self, *exc) -> None:
        for owner, name, original in reversed(self._undo):
            setattr(owner, name, original)


def make_problem(coarse_mesh, fine_mesh, width: float) -> ArlequinProblem:
    material = IsotropicElastic(young=YOUNG, poisson=POISSON)
    kind = "plane_strain" if coarse_mesh.dim() == 2 else "3d"
    coarse = LinearElastic(coarse_mesh, material, kind=kind)
    fine = LinearElastic(fine_mesh, material, kind=kind)
    patch = Patch(fine, gluing_width=width, weights="ramp", coupling="H1", mediator="coarse")
    return ArlequinProblem(coarse, [patch])


def _best_time(fn: Callable[[], object], repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        gc.collect()
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return float(best)


def _peak_bytes(fn: Callable[[], object]) -> int:
    gc.collect()
    tracemalloc.start()
    try:
        fn()
        return int(tracemalloc.get_traced_memory()[1])
    finally:
        tracemalloc.stop()


def _profile(fn: Callable[[], object], n: int = 25) -> dict:
    prof = cProfile.Profile()
    prof.enable()
    fn()
    prof.disable()
    out = {}
    for key in ("cumulative", "tottime"):
        stream = io.StringIO()
        pstats.Stats(prof, stream=stream).sort_stats(key).print_stats(n)
        out[key] = stream.getvalue().splitlines()
    return out


def run_case(case: str, repeat: int = 3, profile: bool = False) -> dict:
    """Time and measure the coupling build and the stiffness assemblies of one case."""
    t0 = time.perf_counter()
    coarse_mesh, fine_mesh, width = build_meshes(case)
    t_mesh = time.perf_counter() - t0
    dim = fine_mesh.dim()
    scalar = ElementTriP1() if dim == 2 else ElementTetP1()
    lam, mu = lame_parameters(YOUNG, POISSON)
    model_intorder = LinearElastic(coarse_mesh, IsotropicElastic(YOUNG, POISSON)).intorder

    def coupling():
        return make_problem(coarse_mesh, fine_mesh, width).couplings

    def skfem_default():
        basis = Basis(fine_mesh, ElementVector(scalar))
        return asm(linear_elasticity(lam, mu), basis)

    def skfem_model_order():
        basis = Basis(fine_mesh, ElementVector(scalar), intorder=model_intorder)
        return asm(linear_elasticity(lam, mu), basis)

    def model_stiffness():
        kind = "plane_strain" if dim == 2 else "3d"
        return LinearElastic(fine_mesh, IsotropicElastic(YOUNG, POISSON), kind=kind).stiffness()

    from arlequin.geometry.clip3d import warm_up

    warm_up()  # numba's compilation (or cache load) out of the timings
    k = skfem_model_order()
    times: dict[str, float] = {
        "skfem_stiffness_default_quadrature": _best_time(skfem_default, repeat),
        "skfem_stiffness_model_quadrature": _best_time(skfem_model_order, repeat),
        "model_stiffness": _best_time(model_stiffness, repeat),
    }
    peaks: dict[str, int] = {
        "skfem_stiffness_default_quadrature": _peak_bytes(skfem_default),
        "skfem_stiffness_model_quadrature": _peak_bytes(skfem_model_order),
        "model_stiffness": _peak_bytes(model_stiffness),
    }
    out: dict = {
        "case": case,
        "coarse_cells": int(coarse_mesh.nelements),
        "fine_cells": int(fine_mesh.nelements),
        "fine_nodes": int(fine_mesh.nvertices),
        "fine_dofs": int(dim * fine_mesh.nvertices),
        "stiffness_nnz": int(k.nnz),
        "model_intorder": int(model_intorder),
        "mesh_build_s": float(t_mesh),
    }
    del k
    phases: dict[str, float] = {}
    best = np.inf
    try:
        for _ in range(repeat):
            gc.collect()
            with PhaseTimer() as timer:
                t0 = time.perf_counter()
                pcs = coupling()
                total = time.perf_counter() - t0
            if total < best:
                best = total
                phases = dict(timer.times)
                phases["other"] = total - sum(timer.times.values())
        peaks["coupling"] = _peak_bytes(coupling)
    except MemoryError as exc:
        # the phases completed before the failure, and the one that failed (partial time)
        failed = {key: float(v) for key, v in timer.times.items()}
        out.update(
            coupling_error=f"MemoryError: {exc}",
            coupling_phases_before_error_s=failed,
            coupling_elapsed_before_error_s=time.perf_counter() - t0,
            time_s=times,
            peak_tracemalloc_bytes=peaks,
            maxrss_bytes=_maxrss_bytes(),
        )
        return out
    times["coupling"] = float(best)
    pc = pcs[0]
    # the target compares with scikit-fem's own assembly at its default quadrature (the faster)
    ref = "skfem_stiffness_default_quadrature"
    target = 4.0 if "n_fine" in CASES[case] else 2.0  # issue 16: nested 2x, non-nested 4x
    out.update(
        overlap_method=pc.overlap.method,
        overlap_coarse_cells=int(np.unique(pc.overlap.coarse_cells).size),
        gluing_cells=int(pc.gluing_cells.size),
        multipliers=int(pc.coupling.n_multipliers),
        time_s=times,
        coupling_phases_s={key: float(v) for key, v in phases.items()},
        peak_tracemalloc_bytes=peaks,
        ratio_time={key: best / v for key, v in times.items() if key != "coupling"},
        ratio_peak={key: peaks["coupling"] / v for key, v in peaks.items() if key != "coupling"},
        ratio_target=target,
        within_target=bool(best <= target * times[ref]),
        maxrss_bytes=_maxrss_bytes(),
    )
    if profile:
        out["profile"] = _profile(coupling)
    out["coupling_alone_maxrss_bytes"] = _coupling_alone_maxrss(case)
    return out


def _coupling_alone_maxrss(case: str) -> int | None:
    """Peak resident memory (bytes) of a child process that builds the meshes and the coupling
    only (the process's own peak, no assembly before it)."""
    cmd = [sys.executable, __file__, "--case", case, "--coupling-only"]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        return None
    return int(json.loads(done.stdout)["maxrss_bytes"])


def _peak_resident_bytes() -> int:
    """This process's own peak resident memory (bytes): VmHWM, which a new program image
    starts afresh (getrusage's ru_maxrss keeps the parent's peak across fork and exec)."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return _maxrss_bytes()


def _maxrss_bytes() -> int:
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(rss if sys.platform == "darwin" else rss * 1024)  # Linux reports KiB


def _run_subprocess(case: str, args: argparse.Namespace) -> dict:
    """Run one case in a child process under a memory (address space) limit and a timeout."""
    cmd = [sys.executable, __file__, "--case", case, "--repeat", str(args.repeat)]
    if args.profile:
        cmd.append("--profile")
    limit = int(args.mem_limit_gb * 2**30)

    def set_limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    t0 = time.perf_counter()
    try:
        done = subprocess.run(
            cmd, capture_output=True, text=True, timeout=args.timeout, preexec_fn=set_limit
        )
    except subprocess.TimeoutExpired:
        return {"case": case, "error": f"timeout after {args.timeout} s", **CASES[case]}
    if done.returncode != 0:
        return {
            "case": case,
            "error": f"exit code {done.returncode} (memory limit {args.mem_limit_gb} GiB)",
            "elapsed_s": time.perf_counter() - t0,
            "stderr_tail": done.stderr.strip().splitlines()[-6:],
            **CASES[case],
        }
    return json.loads(done.stdout)


def main(argv: list[str] | None = None) -> dict:
    """Run the requested cases (each in its own subprocess for ``all``) and print JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", choices=(*CASES, "all"), default="all")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--profile", action="store_true")
    parser.add_argument(
        "--mem-limit-gb", type=float, default=16.0, help="address-space limit per case (GiB)"
    )
    parser.add_argument("--timeout", type=float, default=1800.0, help="time limit per case (s)")
    parser.add_argument("--coupling-only", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.coupling_only:  # the child of _coupling_alone_maxrss
        coarse_mesh, fine_mesh, width = build_meshes(args.case)
        make_problem(coarse_mesh, fine_mesh, width).couplings  # noqa: B018
        result = {"maxrss_bytes": _peak_resident_bytes()}
        print(json.dumps(result))
        return result
    if args.case == "all":
        result = {
            "python": platform.python_version(),
            "numpy": np.__version__,
            "scipy": scipy.__version__,
            "skfem": skfem.__version__,
            "cases": {case: _run_subprocess(case, args) for case in DEFAULT_CASES},
        }
    else:
        result = run_case(args.case, args.repeat, args.profile)
    print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main()
