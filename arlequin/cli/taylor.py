"""The ``arlequin taylor-bar`` command: options, progress bar, summary and JSON.

A thin layer over :func:`arlequin.demos.taylor_bar.run_taylor_bar` (SI units).
"""

from __future__ import annotations

import argparse

from .common import add_out, progress_bar, write_json

__all__ = ["add_taylor_bar", "run_options"]


#: Options that may come with ``--resume`` (the inputs come from the checkpoint).
_RESUME_OPTIONS = {"out", "json", "quiet", "resume", "func", "command", "verbose", "defaults"}


def _cmd_resume(args: argparse.Namespace) -> int:
    from ..demos.taylor_bar import resume_taylor_bar
    from ..demos.taylor_checkpoint import load_checkpoint

    given = sorted(f"--{k.replace('_', '-')}" for k, v in vars(args).items()
                   if k not in _RESUME_OPTIONS and v != args.defaults.get(k))  # fmt: skip
    if given:
        raise ValueError(f"--resume continues with the inputs of the checkpoint; drop {given}")
    if args.out is None:
        raise ValueError("--resume needs --out DIR, the results folder of the interrupted run")
    t_end = load_checkpoint(args.out, None)["call"]["t_end"]
    with progress_bar(t_end * 1e6, "µs", args.quiet, scale=1e6,
                      label="simulated time") as update:  # fmt: skip
        result = resume_taylor_bar(args.out, progress=update)
    print(result.summary())
    write_json(args.json, result.to_json())
    return 0


def run_options(args: argparse.Namespace) -> dict:
    """The keyword arguments of :func:`~arlequin.demos.taylor_bar.run_taylor_bar` that the
    command line gives (all but ``out`` and ``progress``)."""
    laws = ("voce_saturation", "voce_rate", "jc_b", "jc_n", "jc_c", "jc_reference_rate")
    law_params = {k: getattr(args, k) for k in laws if getattr(args, k) is not None}
    # the Arlequin options given on the command line (run_taylor_bar refuses those that do not
    # apply to the model, before any work)
    names = ("patch_length", "gluing_width", "coarse_size", "fine_size", "weights", "mediator",
             "coupling", "coarse_step_ratio", "band_warning", "patch_surface")  # fmt: skip
    arlequin = {k: getattr(args, k) for k in names if getattr(args, k) is not None}
    return dict(
        model=args.model, elements_radial=args.elements_radial, mesh_size=args.mesh_size,
        friction=args.friction, t_end=args.t_end, velocity=args.velocity, young=args.young,
        poisson=args.poisson, density=args.density, yield_stress=args.yield_stress,
        hardening=args.hardening, hardening_law=args.hardening_law, length=args.length,
        radius=args.radius, bulk_viscosity=args.bulk_viscosity, fbar=not args.no_fbar,
        backend=args.backend, geometry=args.geometry, **arlequin, **law_params,
    )  # fmt: skip


def _cmd_taylor_bar(args: argparse.Namespace) -> int:
    from ..demos.taylor_bar import run_taylor_bar

    if args.resume:
        return _cmd_resume(args)
    with progress_bar(args.t_end * 1e6, "µs", args.quiet, scale=1e6,
                      label="simulated time") as update:  # fmt: skip
        result = run_taylor_bar(out=args.out, progress=update, **run_options(args))
    print(result.summary())
    write_json(args.json, result.to_json())
    return 0


def add_taylor_bar(sub) -> None:
    """Register ``arlequin taylor-bar`` on the subcommand parsers ``sub``."""
    p = sub.add_parser(
        "taylor-bar",
        help="Taylor bar impact: a copper bar hits a rigid wall (Arlequin: a coarse elastic bar "
        "plus a refined finite-strain J2 patch; or one mesh)",
        description="A bar (length L, radius R) moving at V hits a rigid frictionless wall at "
        "t = 0. Default (--model arlequin): a coarse linear-elastic model of the whole bar and a "
        "refined finite-strain J2 patch over the impacted end, glued by a mediator in a band at "
        "the patch's top; --model mono: one finite-strain mesh. Axisymmetric Q1 F-bar cells "
        "(--geometry 3d: a quarter bar of F-bar hexahedra), "
        "central differences with the step re-estimated in the current configuration, the "
        "level-set contact model at the wall (on the patch). SI units; lengths in m, element "
        "edges in the reference configuration. "
        "Reports the final length, the footprint (mushroom) radius, the maximum equivalent "
        "plastic strain and the energy balance error (a fraction).",
    )
    p.add_argument(
        "--geometry",
        choices=["axisymmetric", "3d"],
        default="axisymmetric",
        help="axisymmetric: Q1 cells of the (r, z) section (default); 3d: the quarter bar "
        "x, y >= 0 of F-bar hexahedra on an O-grid section, symmetry conditions on x = 0 and "
        "y = 0 (energies and forces of the quarter)",
    )
    p.add_argument(
        "--patch-surface",
        default=None,
        metavar="FILE",
        help="arlequin, --geometry 3d: the patch region as a closed surface (STL/OBJ/PLY, m): "
        "the coarse cells whose centroid lies inside are refined (it must hold the impact face)",
    )
    p.add_argument(
        "--model",
        choices=["arlequin", "mono", "graded"],
        default="arlequin",
        help="arlequin: coarse elastic bar + refined elastoplastic patch; mono: one uniform "
        "finite-strain mesh; graded: one conforming mesh, fine over the patch region, coarse "
        "above, a 2:1 transition row",
    )
    size = p.add_mutually_exclusive_group()
    size.add_argument(
        "--elements-radial",
        type=int,
        default=None,
        metavar="N",
        help="cells across the radius (default 10; arlequin: of the patch); the axial count "
        "is round(L/h)",
    )
    size.add_argument(
        "--mesh-size",
        type=float,
        default=None,
        metavar="H",
        help="cell edge across the radius (m; arlequin: an alias of --fine-size)",
    )
    size.add_argument(
        "--fine-size",
        type=float,
        default=None,
        metavar="H",
        help="arlequin: the patch's cell edge (m; default R/10)",
    )
    p.add_argument(
        "--coarse-size",
        type=float,
        default=None,
        metavar="H",
        help="arlequin: the coarse cell edge (m), a multiple of the fine size (default 2x)",
    )
    p.add_argument(
        "--patch-length",
        type=float,
        default=None,
        metavar="LP",
        help="arlequin: patch length from the impact face (m, default 0.9 L; whole coarse rows)",
    )
    p.add_argument(
        "--gluing-width",
        type=float,
        default=None,
        metavar="W",
        help="arlequin: gluing band width at the patch's top (m, default 2 coarse rows)",
    )
    p.add_argument("--weights", choices=["ramp", "constant"], default=None,
                   help="arlequin: partition weights across the band (default ramp)")  # fmt: skip
    p.add_argument("--mediator", choices=["coarse", "fine"], default=None,
                   help="arlequin: mediator space (default fine)")  # fmt: skip
    p.add_argument("--coupling", choices=["L2", "H1"], default=None,
                   help="arlequin: coupling operator (default H1)")  # fmt: skip
    p.add_argument(
        "--friction",
        type=float,
        default=0.0,
        metavar="MU",
        help="Coulomb friction between the bar and the wall (0: frictionless)",
    )
    p.add_argument(
        "--coarse-step-ratio",
        type=int,
        default=None,
        metavar="M",
        help="arlequin: multi-time-step, at most M patch steps per coarse step (default 1)",
    )
    p.add_argument(
        "--band-warning",
        type=float,
        default=None,
        metavar="EPS",
        help="arlequin: warn if the plastic strain in the gluing band exceeds this (default 0.02)",
    )
    p.add_argument("--t-end", type=float, default=80e-6, metavar="T", help="end time (s)")
    p.add_argument("--velocity", type=float, default=227.0, metavar="V", help="impact speed (m/s)")
    p.add_argument("--young", type=float, default=117e9, metavar="E", help="Young's modulus (Pa)")
    p.add_argument("--poisson", type=float, default=0.35, metavar="NU", help="Poisson's ratio")
    p.add_argument("--density", type=float, default=8930.0, metavar="RHO", help="density (kg/m^3)")
    p.add_argument(
        "--yield-stress", type=float, default=0.4e9, metavar="S", help="initial yield stress (Pa)"
    )
    p.add_argument(
        "--hardening",
        type=float,
        default=0.1e9,
        metavar="H",
        help="linear hardening modulus (Pa; the linear term of the Voce law)",
    )
    p.add_argument("--hardening-law", choices=["linear", "voce", "johnson-cook"], default="linear")
    p.add_argument(
        "--voce-saturation",
        type=float,
        default=None,
        metavar="Q",
        help="Voce: saturation stress Q (Pa, default 0.1e9)",
    )
    p.add_argument(
        "--voce-rate",
        type=float,
        default=None,
        metavar="B",
        help="Voce: saturation rate b (default 10)",
    )
    p.add_argument(
        "--jc-b",
        type=float,
        default=None,
        metavar="B",
        help="Johnson-Cook: B (Pa, default 0.292e9; A is --yield-stress)",
    )
    p.add_argument(
        "--jc-n",
        type=float,
        default=None,
        metavar="N",
        help="Johnson-Cook: exponent n (default 0.31)",
    )
    p.add_argument(
        "--jc-c",
        type=float,
        default=None,
        metavar="C",
        help="Johnson-Cook: strain-rate coefficient C (default 0: off)",
    )
    p.add_argument(
        "--jc-reference-rate",
        type=float,
        default=None,
        metavar="R",
        help="Johnson-Cook: reference strain rate (1/s, default 1)",
    )
    p.add_argument("--length", type=float, default=32.4e-3, metavar="L", help="bar length (m)")
    p.add_argument("--radius", type=float, default=3.2e-3, metavar="R", help="bar radius (m)")
    p.add_argument(
        "--bulk-viscosity",
        action="store_true",
        help="artificial bulk viscosity (linear 0.06, quadratic 1.5)",
    )
    p.add_argument(
        "--no-fbar",
        action="store_true",
        help="plain Q1 cells (they lock under plastic flow; for comparison)",
    )
    p.add_argument(
        "--backend",
        choices=["auto", "numba", "numpy"],
        default="auto",
        help="internal-force path (auto: the compiled kernel)",
    )
    p.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_out(p)
    p.add_argument(
        "--resume",
        action="store_true",
        help="continue the interrupted run of --out DIR from its last checkpoint (written every "
        "10 µs of simulated time), with its recorded inputs",
    )
    p.set_defaults(func=_cmd_taylor_bar)
    p.set_defaults(defaults={a.dest: a.default for a in p._actions})
