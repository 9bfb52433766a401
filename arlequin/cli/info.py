"""``arlequin info``: the versions of the stack, off-screen rendering, numba's and BLAS's threads.

What a bug report needs and what decides whether the demos can draw their pictures here.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import os
import platform

from .common import write_json

__all__ = ["add_info", "environment_report"]

#: The distributions reported, in order.
STACK = ("arlequin", "numpy", "scipy", "scikit-fem", "meshio", "h5py", "trimesh", "pyvista",
         "vtk", "numba", "threadpoolctl", "matplotlib", "tqdm")  # fmt: skip


def _offscreen_rendering() -> str:
    """ "yes (<renderer>)" if pyvista can render a picture off-screen here, else "no: <why>"."""
    try:
        from ..demos.render import _offscreen

        pv = _offscreen()
        plotter = pv.Plotter(off_screen=True, window_size=(16, 16))
        plotter.add_mesh(pv.Sphere())
        plotter.screenshot(return_img=True)
        name = type(plotter.ren_win).__name__
        plotter.close()
        return f"yes ({name})"
    except Exception as exc:  # any failure means no pictures: say why
        return f"no: {type(exc).__name__}: {exc}"


def environment_report(render: bool = True) -> dict:
    """Python, the platform, the versions of :data:`STACK`, numba's threads and (``render``)
    whether off-screen pictures work."""
    versions = {}
    for dist in STACK:
        try:
            versions[dist] = importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            versions[dist] = None
    try:
        import numba

        threads = {"numba_threads": int(numba.get_num_threads()),
                   "numba_threading_layer": numba.config.THREADING_LAYER}  # fmt: skip
    except ImportError:  # pragma: no cover (numba is a dependency)
        threads = {"numba_threads": None, "numba_threading_layer": None}
    threads["omp_wait_policy"] = os.environ.get("OMP_WAIT_POLICY")
    try:
        from threadpoolctl import threadpool_info

        threads["blas"] = [f"{p['internal_api']} {p.get('version')}: {p['num_threads']} threads"
                           for p in threadpool_info() if p["user_api"] == "blas"]  # fmt: skip
    except ImportError:  # pragma: no cover (threadpoolctl is a dependency)
        threads["blas"] = []
    report = {"python": platform.python_version(), "platform": platform.platform(),
              "versions": versions, **threads}  # fmt: skip
    if render:
        report["offscreen_rendering"] = _offscreen_rendering()
    return report


def _cmd_info(args: argparse.Namespace) -> int:
    report = environment_report(render=not args.no_render)
    write_json(args.json, report)
    print(f"python {report['python']} on {report['platform']}")
    for dist, version in report["versions"].items():
        print(f"  {dist:<12} {version or 'not installed'}")
    print(f"numba threads: {report['numba_threads']} "
          f"(threading layer setting: {report['numba_threading_layer']}; OMP_WAIT_POLICY "
          f"{report['omp_wait_policy']})")  # fmt: skip
    for blas in report["blas"]:
        print(f"BLAS: {blas} (one in the explicit time loop)")
    if "offscreen_rendering" in report:
        print(f"off-screen pictures: {report['offscreen_rendering']}")
    return 0


def add_info(sub) -> None:
    """Register ``arlequin info`` on the subcommand parsers ``sub``."""
    p = sub.add_parser("info", help="versions of the stack, off-screen rendering, numba threads")
    p.add_argument("--json", metavar="PATH", default=None, help="write the report as JSON")
    p.add_argument("--no-render", action="store_true",
                   help="skip the off-screen rendering check (it opens a window)")  # fmt: skip
    p.set_defaults(func=_cmd_info)
