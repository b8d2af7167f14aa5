"""Command line of dvstatic.

::

    dvstatic run SCENE [--out DIR] [--set key=value ...] [--overwrite] [--quiet]
    dvstatic validate [--quick] [--only fig05,fig10] [--dir validation] [--out DIR]
    dvstatic bench [--quick] [--dir validation]
    dvstatic demo
    dvstatic --version

validate --quick takes about 4 minutes on 2 cores, bench --quick about 3; both print
each script's time and the total.

Exit codes: 0 success, 2 bad input (scene, arguments, files, a missing optional
engine), 3 the solver refused or failed (unstable lattice, no convergence), 4 best
effort: an unconverged result was written, 130 interrupted.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import subprocess
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from ._version import __version__
from .console import print_summary
from .errors import InputError, MissingDependencyError, SolverError, UnknownRegionError

log = logging.getLogger("dvstatic")


def _demo(args: argparse.Namespace) -> int:
    """Paper exp. 3 on a lattice: uniaxial compression of the unit square, DV and RV
    against the analytic plane-stress solution, with direct and AMG solves."""
    from .lattice import DV, RV
    from .mesh import rectangle
    from .problem import Fix, Traction
    from .solvers import solve

    E, nu = 1e5, 0.2
    print("dvstatic demo: unit square, sigma_xx = -1 (paper exp. 3), E = 1e5, nu = 0.2")
    print(
        f"{'model':5} {'h':>7} {'nodes':>7} {'solver':>6} {'iters':>5} {'L2 error':>9} "
        f"{'u_x(right)':>11} {'exact':>11} {'seconds':>8}"
    )
    for h in args.h:
        mesh = rectangle(1.0, 1.0, h, kind="lattice")
        exact = np.c_[-mesh.points[:, 0] / E, nu * mesh.points[:, 1] / E]
        for cls in (DV, RV):
            model = cls(mesh, E, nu)
            for solver in ("direct", "amg"):
                t0 = time.perf_counter()
                sol = solve(
                    model,
                    [Fix("left", x=0), Fix("bottom", y=0)],
                    [Traction("right", (-1.0, 0.0))],
                    solver=solver,
                )
                dt = time.perf_counter() - t0
                err = np.linalg.norm(sol.u - exact) / np.linalg.norm(exact)
                ux = sol.u[mesh.part_nodes("right"), 0].mean()
                print(
                    f"{cls.kind:5} {h:7.4f} {mesh.n_points:7d} {solver:>6} "
                    f"{sol.info.iterations:5d} {err:9.2e} {ux:11.4e} {-1 / E:11.4e} "
                    f"{dt:8.3f}"
                )
    return 0


def _show_progress(args) -> bool:
    return not args.quiet and sys.stderr.isatty()


def _run(args: argparse.Namespace) -> int:
    from . import scene
    from .solvers import solve

    sc = scene.load(args.scene, args.set or ())
    folder = _output_folder(sc, args)
    t0 = time.perf_counter()
    say = _Stages(not args.quiet)
    say("building the mesh")
    mesh = sc.build_mesh()
    say(f"calibrating the model on {mesh.n_points} nodes")
    model = sc.build_model(mesh)
    supports = sc.build_supports(mesh)
    loads = sc.build_loads(mesh)
    sc.check_outputs(mesh)  # before the solve, not after it
    if sc.data["fracture"] is not None:
        return _run_fracture(sc, model, supports, loads, folder, args, say, t0)
    say(f"solving ({model.kind}, {2 * mesh.n_points} dof)")
    try:
        sol = solve(model, supports, loads, progress=_show_progress(args), **sc.solve_options())
    except InputError as exc:  # e.g. supports that leave a rigid motion free
        raise scene.SceneError(sc.path, _solve_error_key(scene, exc), str(exc)) from None
    except SolverError as exc:
        exc.args = (f"{sc.path}: {exc}",)
        raise
    if sol.u is None:  # an MPI rank other than 0 of a solver="petsc" run: rank 0 writes
        return 0
    fe, fe_failed = _fe_reference(sc, mesh, supports, loads, say, sol.info.nonlinear)
    say("recovering stresses and writing the outputs")
    data, written = _write_outputs(sc, sol, fe, folder, args, t0, fe_failed)
    print_summary(sc, data, written)
    if not sol.info.converged:
        print(
            f"warning: the solution did NOT converge (best effort): {sol.info.failure}",
            file=sys.stderr,
        )
        return 4
    return 0


def _run_fracture(sc, model, supports, loads, folder, args, say, t0: float) -> int:
    """``[fracture]``: the event-driven analysis, its JSON, curve and VTU series."""
    from . import io
    from .crack import fracture
    from .report import fracture_checks, fracture_lines

    opts = sc.fracture_options()
    opts["held"] = sc.build_loads(model.mesh, held=True) or None
    n = opts["options"].max_events
    say(
        f"fracture ({model.kind}, {2 * model.mesh.n_points} dof, up to {n} events; Ctrl-C "
        "stops and keeps the events so far)"
    )
    try:
        res = fracture(model, supports, loads, progress=_show_progress(args), **opts)
    except UnknownRegionError as exc:  # a [[fracture.regions]] name the mesh lacks
        names = [r["name"] for r in sc.data["fracture"]["regions"]]
        key = f"fracture.regions[{names.index(exc.region)}].name" if exc.region in names else ""
        raise _scene_error(sc, key or "fracture.regions", exc) from None
    except InputError as exc:
        raise _scene_error(sc, _fracture_key(sc, exc.param), exc) from None
    say("writing the outputs")
    o, name = sc.data["output"], sc.name
    with _staged(folder) as stage:
        written = []
        data = res.to_dict()
        data["checks"] = fracture_checks(res, sc.data["fracture"]["checks"])
        data["model"] = repr(res.model)  # the lattice that broke (no exact cells)
        data["scene"] = _scene_record(sc, args)
        data["dvstatic_version"] = __version__
        data["created"] = datetime.now(UTC).isoformat(timespec="seconds")
        data["seconds_total"] = time.perf_counter() - t0
        if o["png"] and res.events:
            curve = io.write_fracture_curve(
                stage / f"{name}_curve.png", res, sc.data["title"] or None, data["checks"]
            )
            crack = io.write_crack_png(stage / f"{name}_crack.png", res, sc.data["title"] or None)
            written += [curve.name, crack.name]
        if o["vtu"]:
            pvd = io.write_fracture_series(stage / f"{name}_fracture", res, name)
            series = sorted(p.relative_to(stage).as_posix() for p in pvd.parent.iterdir())
            written += [pvd.relative_to(stage).as_posix()] + [
                n for n in series if not n.endswith(".pvd")
            ]
        written.append(io.write_json(stage / f"{name}_fracture.json", data).name)
        final = folder.commit(written, owner=_owner(sc))
    title = f"{sc.data['title'] or sc.name}"
    shown = [p for p in final if p.suffix != ".vtu" or p.parent == folder.path]
    print("\n".join(fracture_lines(res, data["checks"], title, shown)))
    return 130 if res.stop_reason == "interrupted" else 0


def _planned_outputs(sc) -> list[str]:
    """The files a run of the scene writes whatever its results (relative to the
    output folder): checked before any work starts."""
    o, name = sc.data["output"], sc.name
    if sc.data["fracture"] is not None:
        return [
            *([f"{name}_curve.png", f"{name}_crack.png"] if o["png"] else []),
            *([f"{name}_fracture/{name}.pvd"] if o["vtu"] else []),
            f"{name}_fracture.json",
        ]
    return [
        *([f"{name}.vtu", f"{name}_bonds.vtu"] if o["vtu"] else []),
        *([f"{name}.png"] if o["png"] else []),
        *([f"{name}.json"] if o["json"] else []),
    ]


def _output_folder(sc, args):
    """The run's output folder, checked before any work: ``--out`` or
    ``<scene name>-out``; refuses a file, outputs that would replace an input, and
    existing outputs without ``--overwrite``."""
    from .outfolder import OutputFolder

    out = Path(args.out) if args.out else Path(f"{sc.name}-out")
    inputs = [sc.path]
    if sc.data["mesh"]["type"] == "file":
        mesh_file = Path(sc.data["mesh"]["path"])
        inputs.append(mesh_file if mesh_file.is_absolute() else sc.path.parent / mesh_file)
    folder = OutputFolder(out, overwrite=args.overwrite, protect=inputs)
    folder.check(_planned_outputs(sc))
    return folder


def _owner(sc) -> str:
    """The scene file as the manifest records the files it wrote."""
    return str(Path(sc.path).resolve())


def _scene_record(sc, args) -> dict:
    return {
        "file": str(sc.path),
        "title": sc.data["title"],
        "overrides": list(args.set or ()),
        "resolved": sc.data,  # every key, defaults filled in
    }


@contextlib.contextmanager
def _staged(folder):
    """The folder's staging area; says what was (not) written if the block fails."""
    try:
        with folder.staging() as stage:
            yield stage
    except BaseException as exc:
        print(
            "stopped before the outputs were complete: nothing was written "
            f"({folder.path} {folder.state()})",
            file=sys.stderr,
        )
        exc.dvstatic_reported = True
        raise


def _fracture_key(sc, param: str) -> str:
    """The scene key of an input error of ``dv.fracture`` (``param`` as it names it)."""
    if param in ("supports", "loads", "mesh", "model"):
        return param
    if param == "held":
        return "fracture.held"
    name, _, region = param.partition("[")
    region = region.strip("'\"]")
    for i, r in enumerate(sc.data["fracture"]["regions"]):
        if region and r["name"] == region:
            return f"fracture.regions[{i}].{name}"
    if region:  # a region that the mesh does not have
        return "fracture.regions"
    return f"fracture.{param}"


def _scene_error(sc, key: str, exc: Exception):
    from . import scene

    return scene.SceneError(sc.path, key, str(exc))


class _Stages:
    """One line on stderr as each stage of a run starts (none with ``--quiet``)."""

    def __init__(self, on: bool):
        self.on, self.t0 = on, time.perf_counter()

    def __call__(self, text: str) -> None:
        if self.on:
            print(f"[{time.perf_counter() - self.t0:6.1f} s] {text} ...", file=sys.stderr)


def _fe_reference(sc, mesh, supports, loads, say, nonlinear: bool):
    """The FE solution of ``[output] fe_compare`` and why there is none: (None, "") if
    not asked for; (None, reason) where it failed or does not apply (a nonlinear
    solution against a linear reference). A failed reference never costs the lattice
    result: that is written, and the reason said."""
    o = sc.data["output"]
    if not o["fe_compare"]:
        return None, ""
    if nonlinear:
        why = "the FE reference is linear, the solution nonlinear: not compared"
        print(f"note: {why}", file=sys.stderr)
        return None, why
    dof = _fe_dof(mesh, o["fe_order"], o["fe_refine"])
    mesh_words = {0: "on the lattice's triangles", 1: "refined once"}.get(
        o["fe_refine"], f"refined {o['fe_refine']} times"
    )
    say(
        f"FE reference (P{o['fe_order']} {mesh_words}, {dof:,} dof, "
        f"roughly {max(1.0, 10.0 * (dof / 2.8e5) ** 1.2):.0f} s on 2 cores)"
    )
    try:
        return _fe_solve(sc, mesh, supports, loads), ""
    except (SolverError, InputError) as exc:
        why = f"the FE reference failed ({exc}); the lattice results are written without it"
        print(f"warning: {why}", file=sys.stderr)
        return None, why
    except KeyboardInterrupt:  # the lattice result is computed: keep it
        why = "the FE reference was interrupted; the lattice results are written without it"
        print(f"note: {why}; Ctrl-C again stops before they are", file=sys.stderr)
        return None, why


def _fe_dof(mesh, order: int, refine: int) -> int:
    """Unknowns of the FE reference: each uniform refinement makes V + E vertices,
    2 E + 3 T edges and 4 T triangles; Pk adds k - 1 nodes per edge and
    (k - 1)(k - 2) / 2 per triangle (the estimate of its time: 10 s for 2.8e5 dof,
    plate_with_hole refined once, measured with AMG-CG)."""
    v, t = mesh.n_points, len(mesh.triangles)
    e = v + t - 1  # Euler, one body without holes (holes change it by a few)
    for _ in range(refine):
        v, e, t = v + e, 2 * e + 3 * t, 4 * t
    return 2 * (v + (order - 1) * e + (order - 1) * (order - 2) // 2 * t)


def _fe_solve(sc, mesh, supports, loads):
    from . import fem

    o, mat = sc.data["output"], sc.data["material"]
    return fem.solve(
        mesh,
        mat["E"],
        mat["nu"],
        supports,
        loads,
        order=o["fe_order"],
        refine=o["fe_refine"],
        plane=mat["plane"],
        thickness=mat["thickness"],
        materials={m["region"]: (m["E"], m["nu"]) for m in sc.data["materials"]} or None,
    )


def _write_outputs(
    sc, sol, fe, folder, args, t0: float, fe_failed: str = ""
) -> tuple[dict, list[Path]]:
    """Write VTU, PNG and JSON into the output folder's staging area and move them onto
    their names only when all are complete: an interrupted or failed run leaves
    earlier results as they were. Returns the summary data and the paths written."""
    from . import io

    o = sc.data["output"]
    # one stress recovery for every output: nonlinear solutions have only the virial
    method = None if sol.info.nonlinear else o["stress"]
    with _staged(folder) as stage:
        written: list[str] = []
        if o["vtu"]:
            written.append(io.write_vtu(stage / f"{sc.name}.vtu", sol, fe=fe).name)
            written.append(io.write_bonds_vtu(stage / f"{sc.name}_bonds.vtu", sol).name)
        view = io.picture_view(sol, o["view"], method, o["field"])
        scale = o["scale"] or io.default_scale(sol, view)
        if o["png"]:
            png = io.write_png(
                stage / f"{sc.name}.png",
                sol,
                field=o["field"],
                scale=scale,
                title=sc.data["title"] or None,
                stress=method,
                view=view,
            )
            written.append(png.name)
        data = io.summary(
            sol,
            fe=fe,
            probes=o["probes"] or None,
            part_stress=o["part_stress"],
            stress=method,
            checks=o["checks"],
        )
        data["scene"] = _scene_record(sc, args)
        if fe_failed:
            data["fe_reference"] = fe_failed
        if o["png"]:
            data["picture"] = {
                "file": png.name,
                "field": o["field"],
                "magnification": scale,
                "view": list(view),
            }
        data["dvstatic_version"] = __version__
        data["created"] = datetime.now(UTC).isoformat(timespec="seconds")
        data["seconds_total"] = time.perf_counter() - t0
        if o["json"]:
            written.append(io.write_json(stage / f"{sc.name}.json", data).name)
        final = folder.commit(written, owner=_owner(sc))
    args.written = final  # what a Ctrl-C from here on leaves behind
    return data, final


def _solve_error_key(scene, exc: InputError) -> str:
    """The scene key an input error of ``solve()`` is about ("" when none is)."""
    options = {name: key for key, name in scene.SOLVER_KEYS.items()}
    if exc.param in options:
        return f"solver.{options[exc.param]}"
    return "supports" if exc.param == "supports" else ""


def _scripts_dir(arg: str | None) -> Path:
    cands = (
        [Path(arg)]
        if arg
        else [Path.cwd() / "validation", Path(__file__).resolve().parents[1] / "validation"]
    )
    for c in cands:
        if (c / "_common.py").is_file():
            return c
    raise FileNotFoundError(
        "validation scripts not found (looked in " + ", ".join(map(str, cands)) + "); run "
        "from a source checkout of dvstatic or pass --dir path/to/validation"
    )


def _run_scripts(names: list[Path], extra: list[str], args) -> int:
    from tqdm import tqdm

    failed = []
    t_all = time.perf_counter()
    bar = tqdm(names, desc="scripts", unit="script", disable=not _show_progress(args))
    for i, path in enumerate(bar):
        bar.set_postfix_str(path.stem)
        if not args.quiet and bar.disable:  # no bar (not a terminal): a line per script
            print(f"[{i + 1}/{len(names)}] {path.stem} ...", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, str(path), *extra], capture_output=True, text=True, check=False
        )
        if not args.quiet:
            tqdm.write(proc.stdout.rstrip())
            tqdm.write(f"-- {path.stem}: {time.perf_counter() - t0:.0f} s")
        if proc.returncode != 0:
            failed.append(path.stem)
            tqdm.write(f"FAILED {path.stem}:\n{proc.stderr.rstrip()}")
    if not args.quiet:
        total = time.perf_counter() - t_all
        print(f"{len(names)} script(s) in {total / 60:.1f} min", file=sys.stderr)
    if failed:
        print(f"{len(failed)} script(s) failed: {', '.join(failed)}", file=sys.stderr)
        return 3
    return 0


def _validate(args: argparse.Namespace) -> int:
    d = _scripts_dir(args.dir)
    scripts = sorted(d.glob("fig[0-9][0-9]_*.py")) + [
        d / "elastica.py",
        d / "convergence.py",
        d / "stress.py",
        d / "refinement.py",
        d / "fracture.py",
        d / "biaxial.py",
    ]
    if args.only:
        want = [w.strip() for w in args.only.split(",") if w.strip()]
        known = {p.stem.split("_")[0]: p for p in scripts}
        known.update({p.stem: p for p in scripts})
        bad = [w for w in want if w not in known]
        if bad:
            raise ValueError(
                f"--only: unknown script(s) {', '.join(bad)}; accepted: "
                f"{', '.join(sorted(k for k in known if '_' not in k))}"
            )
        scripts = [known[w] for w in want]
    extra = ["--quick"] if args.quick else []
    if args.out:
        extra += ["--out", str(args.out)]
    return _run_scripts(scripts, extra, args)


def _bench(args: argparse.Namespace) -> int:
    d = _scripts_dir(args.dir)
    scripts = sorted(d.glob("bench_*.py"))
    return _run_scripts(scripts, ["--quick"] if args.quick else [], args)


def _help_text() -> str:
    """The module docstring without its reST markup (``::`` and the indent)."""
    lines = [ln for ln in __doc__.strip().splitlines() if ln.strip() != "::"]
    return "\n".join(ln[4:] if ln.startswith("    ") else ln for ln in lines)


def _parser() -> argparse.ArgumentParser:
    """The command line: ``run``, ``validate``, ``bench``, ``demo``."""
    parser = argparse.ArgumentParser(
        prog="dvstatic",
        description=_help_text(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"dvstatic {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    verbose = argparse.ArgumentParser(add_help=False)  # -v after the command, too
    verbose.add_argument(
        "-v", "--verbose", dest="verbose_here", action="store_true", help="log progress details"
    )
    sub = parser.add_subparsers(dest="command")
    p_run = sub.add_parser(
        "run", parents=[verbose], help="solve a scene file and write its outputs"
    )
    p_run.add_argument("scene", help="scene file (TOML), see docs/scenes.md")
    p_run.add_argument("--out", help="output folder (default: <scene name>-out)")
    p_run.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="override a scene value, e.g. --set mesh.h=0.05 (repeatable)",
    )
    p_run.add_argument(
        "--overwrite",
        action="store_true",
        help="replace this run's files where they exist (nothing else is touched)",
    )
    p_run.add_argument("-q", "--quiet", action="store_true", help="no progress bars")
    p_run.set_defaults(func=_run)

    p_val = sub.add_parser(
        "validate", parents=[verbose], help="run the validation scripts (paper figures 4-10)"
    )
    p_val.add_argument(
        "--quick",
        action="store_true",
        help="CI sizes (about 4 minutes on 2 cores; the full sizes take hours)",
    )
    p_val.add_argument("--only", help="comma-separated list, e.g. fig05,fig10,elastica")
    p_val.add_argument("--dir", help="folder of the validation scripts")
    p_val.add_argument(
        "--out", help="output folder (default: validation/out; validation/out/quick with --quick)"
    )
    p_val.add_argument("-q", "--quiet", action="store_true", help="no progress, no tables")
    p_val.set_defaults(func=_validate)

    p_bench = sub.add_parser("bench", parents=[verbose], help="run the benchmarks")
    p_bench.add_argument(
        "--quick", action="store_true", help="small sizes only (about 3 minutes on 2 cores)"
    )
    p_bench.add_argument("--dir", help="folder of the benchmark scripts")
    p_bench.add_argument("-q", "--quiet", action="store_true", help="no progress, no tables")
    p_bench.set_defaults(func=_bench)

    demo = sub.add_parser("demo", parents=[verbose], help="solve paper exp. 3 and print a table")
    demo.add_argument(
        "--h",
        type=float,
        nargs="+",
        default=[0.05, 0.025, 0.0125],
        help="lattice spacings (default: 0.05 0.025 0.0125)",
    )
    demo.set_defaults(func=_demo)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    args.verbose = args.verbose or getattr(args, "verbose_here", False)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    for handler in logging.getLogger().handlers:  # the CLI says it once, at the end
        handler.addFilter(lambda record: not getattr(record, "best_effort", False))
    if not getattr(args, "command", None):
        parser.print_help()
        return 2
    try:
        return args.func(args)
    except SolverError as exc:
        print(f"error: the solver refused or failed: {exc}", file=sys.stderr)
        return 3
    except MissingDependencyError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except (ValueError, TypeError, FileNotFoundError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a folder that cannot be written, a full disk
        print(f"error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "), file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        written = getattr(args, "written", None)
        if args.command != "run" or getattr(exc, "dvstatic_reported", False):
            print("interrupted", file=sys.stderr)
        elif written:
            print(f"interrupted; the outputs were written: {written[0].parent}", file=sys.stderr)
        else:
            print(
                "interrupted before any output was written: files already in the output "
                "folder are as they were",
                file=sys.stderr,
            )
        return 130


if __name__ == "__main__":
    sys.exit(main())
