"""Command line: ``dvstatic demo`` and ``dvstatic --version``."""

from __future__ import annotations

import argparse
import logging
import sys
import time

import numpy as np

from . import __version__


def _demo(args: argparse.Namespace) -> int:
    """Paper exp. 3 on a lattice: uniaxial compression of the unit square, DV and RV
    against the analytic plane-stress solution, with direct and AMG solves."""
    import dvstatic as dv

    E, nu = 1e5, 0.2
    print("dvstatic demo: unit square, sigma_xx = -1 (paper exp. 3), E = 1e5, nu = 0.2")
    print(
        f"{'model':5} {'h':>7} {'nodes':>7} {'solver':>6} {'iters':>5} {'L2 error':>9} "
        f"{'u_x(right)':>11} {'exact':>11} {'seconds':>8}"
    )
    for h in args.h:
        mesh = dv.mesh.rectangle(1.0, 1.0, h, kind="lattice")
        exact = np.c_[-mesh.points[:, 0] / E, nu * mesh.points[:, 1] / E]
        for cls in (dv.DV, dv.RV):
            model = cls(mesh, E, nu)
            for solver in ("direct", "amg"):
                t0 = time.perf_counter()
                sol = dv.solve(
                    model,
                    [dv.Fix("left", x=0), dv.Fix("bottom", y=0)],
                    [dv.Traction("right", (-1.0, 0.0))],
                    solver=solver,
                )
                dt = time.perf_counter() - t0
                err = np.linalg.norm(sol.u - exact) / np.linalg.norm(exact)
                ux = sol.u[mesh.part_nodes("right"), 0].mean()
                print(
                    f"{cls.kind:5} {h:7.4f} {mesh.n_points:7d} {solver:>6} "
                    f"{sol.info['iterations']:5d} {err:9.2e} {ux:11.4e} {-1 / E:11.4e} "
                    f"{dt:8.3f}"
                )
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="dvstatic", description=__doc__)
    parser.add_argument("--version", action="version", version=f"dvstatic {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress")
    sub = parser.add_subparsers(dest="command")
    demo = sub.add_parser("demo", help="solve paper exp. 3 and print a table")
    demo.add_argument(
        "--h",
        type=float,
        nargs="+",
        default=[0.05, 0.025, 0.0125],
        help="lattice spacings (default: 0.05 0.025 0.0125)",
    )
    demo.set_defaults(func=_demo)
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    if not getattr(args, "command", None):
        parser.print_help()
        return 2
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
