"""The FE reference's price and accuracy in the examples (issue 27).

Every example with ``fe_compare`` runs three times with ``dvstatic run`` in a fresh
process: without the reference, with it as the scene has it (the default: P2 on the
lattice's own triangles), and with a finer one: one element order up on the same
triangles (P4: refined once more). The third run estimates the reference's own error
at every printed check, ``|fe - fe_finer|``, and the lattice's,
``|lattice - fe_finer|``; their ratio says how much more accurate the reference is.
Each run's wall time and peak memory (``wait4`` of the child) are recorded; the ratio
"with / without" is what the reference costs.

Usage::

    python validation/bench_fe_reference.py           # the seven examples
    python validation/bench_fe_reference.py --quick   # beam and tunnel

Writes ``validation/out/bench_fe_reference.json`` (``--quick``: ``validation/out/quick/``)
and prints a table.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

from _common import parser, write_json

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = (
    "beam",
    "plate_with_hole",
    "tunnel",
    "thick_cylinder",
    "inclusion",
    "layered_slope",
    "brazilian_disc",
)
QUICK = ("beam", "tunnel")


def run(example: str, out: Path, *settings: str) -> dict:
    """``dvstatic run`` in a child process: its JSON summary, wall seconds, peak MB."""
    cmd = [sys.executable, "-m", "dvstatic", "run", str(ROOT / "examples" / f"{example}.toml")]
    cmd += ["--out", str(out), "--overwrite", "--quiet"]
    for s in ("output.png=false", "output.vtu=false", *settings):
        cmd += ["--set", s]
    t0 = time.perf_counter()
    child = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - t0
    err = child.stderr.read().decode()
    child.stderr.close()
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{example} {settings}: {err}")
    data = json.loads((out / f"{example}.json").read_text())
    return {"summary": data, "seconds": wall, "peak_mb": usage.ru_maxrss / 1024}


def scene_fe(example: str) -> tuple[int, int]:
    """The scene's FE reference: its element order and refinements."""
    data = tomllib.loads((ROOT / "examples" / f"{example}.toml").read_text())
    out = data.get("output", {})
    return int(out.get("fe_order", 2)), int(out.get("fe_refine", 0))


def finer_settings(order: int, refine: int) -> tuple[str, ...]:
    """The finer reference: one element order up on the same triangles (P4: refined
    once more)."""
    if order < 4:
        return (f"output.fe_order={order + 1}",)
    return (f"output.fe_refine={refine + 1}",)


def measure(example: str, tmp: Path) -> dict:
    order, refine = scene_fe(example)
    bare = run(example, tmp / "bare", "output.fe_compare=false")
    ref = run(example, tmp / "ref")
    finer = run(example, tmp / "finer", *finer_settings(order, refine))
    checks = []
    for c, f in zip(ref["summary"]["checks"], finer["summary"]["checks"], strict=True):
        scale = abs(f["fe_value"]) or 1.0
        lattice = abs(c["value"] - f["fe_value"]) / scale
        fe = abs(c["fe_value"] - f["fe_value"]) / scale
        checks.append(
            {
                "name": c["name"],
                "lattice_error": lattice,
                "fe_error": fe,
                "ratio": lattice / fe if fe > 0 else float("inf"),
            }
        )
    fe = ref["summary"]["fe"]
    return {
        "example": example,
        "nodes": ref["summary"]["mesh"]["nodes"],
        "fe_order": order,
        "fe_refine": refine,
        "finer": list(finer_settings(order, refine)),
        "fe_dof": fe["n_dof"],
        "fe_solver": fe.get("solver"),
        "fe_seconds": fe["seconds"],
        "seconds": {"without": bare["seconds"], "with": ref["seconds"]},
        "peak_mb": {"without": bare["peak_mb"], "with": ref["peak_mb"]},
        "time_ratio": ref["seconds"] / bare["seconds"],
        "memory_ratio": ref["peak_mb"] / bare["peak_mb"],
        "checks": checks,
    }


def main(argv=None) -> int:
    args = parser(__doc__).parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for example in QUICK if args.quick else EXAMPLES:
            r = measure(example, Path(d) / example)
            rows.append(r)
            worst = min(c["ratio"] for c in r["checks"])
            print(
                f"{example:16s} {r['nodes']:7,d} nodes, P{r['fe_order']} refine {r['fe_refine']} "
                f"{r['fe_dof']:8,d} dof "
                f"({r['fe_solver']}): time x{r['time_ratio']:.2f} "
                f"({r['seconds']['with']:.1f} / {r['seconds']['without']:.1f} s), "
                f"memory x{r['memory_ratio']:.2f} "
                f"({r['peak_mb']['with']:.0f} / {r['peak_mb']['without']:.0f} MB), "
                f"more accurate than the lattice by x{worst:.0f} or more",
                flush=True,
            )
            for c in r["checks"]:
                print(
                    f"    {c['name']:42s} lattice {c['lattice_error']:.2e}  "
                    f"reference {c['fe_error']:.2e}  x{c['ratio']:.0f}"
                )
    out = write_json({"quick": args.quick, "rows": rows}, args.out / "bench_fe_reference.json")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
