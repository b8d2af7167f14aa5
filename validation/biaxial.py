"""Biaxial strength of a plate (dv.fracture, criterion "mohr-coulomb"): a square between
frictionless platens under proportional biaxial stress, plane stress and plane strain,
against the 3-D Mohr-Coulomb envelope and Kupfer's biaxial tests of concrete. Prints a
table, writes biaxial.json.

Square 1 x 1 (CVT, h = 0.05 and 0.025; --quick: 0.08), rollers on the left and bottom
sides, pressures on the top (sigma_yy = -p) and right (sigma_xx = -ratio p) growing
together (force control), brittle bonds: the first event is the failure of the uniform
state. Material: E = 3e4, nu = 0.2, fc = 32, ft = 3, phi = 30 deg, the cohesion from
the uniaxial strength (c = fc (1 - sin phi) / (2 cos phi) = 9.24).

References, per unit fc (p at failure):
* 3-D Mohr-Coulomb with the tension cut-off: the largest and the smallest of the three
  principal stresses, sigma_zz = 0 in plane stress and nu (sigma_xx + sigma_yy) in plane
  strain. In plane stress every compression ratio fails at fc.
* the in-plane envelope (sigma_zz left out): what the lattice's in-plane faces alone give,
  as ``criterion="mohr-coulomb"`` did before the out-of-plane test (2.5 fc at 0.2, never
  at 0.52 and 1).
* Kupfer, Hilsdorf & Ruesch (1969), plane-stress tests of concrete: 1.20 / 1.24 / 1.16 fc
  at 0.2 / 0.52 / 1.0 (compression ratios only). Mohr-Coulomb has no intermediate-stress
  effect: it is 14-19 % below them, on the safe side.
"""

from __future__ import annotations

import time

import numpy as np
from _common import parser, write_json

import dvstatic as dv

E, NU, FC, FT, PHI = 3e4, 0.2, 32.0, 3.0, 30.0
C = FC * (1 - np.sin(np.radians(PHI))) / (2 * np.cos(np.radians(PHI)))
RATIOS = (0.0, 0.2, 0.52, 1.0, -0.05, -0.2)
KUPFER = {0.0: 1.0, 0.2: 1.20, 0.52: 1.24, 1.0: 1.16}


def envelope(ratio: float, plane: str, out_of_plane: bool = True) -> float:
    """Failure p / fc of the state sigma_yy = -p, sigma_xx = -ratio p under Mohr-Coulomb
    with the tension cut-off (inf: never): all three principal stresses, or the in-plane
    pair alone (``out_of_plane=False``)."""
    kp = (1 + np.sin(np.radians(PHI))) / (1 - np.sin(np.radians(PHI)))
    s = [-ratio, -1.0]
    if out_of_plane:
        s.append(0.0 if plane == "stress" else -NU * (1 + ratio))
    hi, lo = max(s), min(s)
    p = [FC / (hi * kp - lo)] if hi * kp - lo > 0 else []
    p += [FT / hi] if hi > 0 else []
    return min(p, default=np.inf) / FC


def first_failure(h: float, plane: str, ratio: float, seed: int = 0) -> dict:
    """The first event of one proportional biaxial run."""
    mesh = dv.mesh.rectangle(1.0, 1.0, h, kind="cvt", seed=seed)
    model = dv.DV(mesh, E, NU, plane=plane)
    sup = [dv.Fix("bottom", y=0.0), dv.Fix("left", x=0.0)]
    loads = [dv.Pressure("top", 1.0), dv.Pressure("right", ratio)]
    t0 = time.perf_counter()
    res = dv.fracture(
        model,
        sup,
        loads,
        ft=FT,
        criterion="mohr-coulomb",
        cohesion=C,
        friction_angle=PHI,
        max_events=1,
    )
    ev = res.events[0] if res.events else None
    return {
        "h": h,
        "nodes": mesh.n_points,
        "plane": plane,
        "ratio": ratio,
        "lattice": None if ev is None else ev.load_factor / FC,
        "mode": None if ev is None else ev.mode,
        "stop": res.message if ev is None else None,
        "mohr_coulomb_3d": envelope(ratio, plane),
        "in_plane_only": envelope(ratio, plane, out_of_plane=False),
        "kupfer": KUPFER.get(ratio) if plane == "stress" else None,
        "seconds": time.perf_counter() - t0,
    }


def _fmt(v, missing: str = "never") -> str:
    if v is None:
        return missing
    return "never" if not np.isfinite(v) else f"{v:.4f}"


def table(hs) -> list[dict]:
    rows = []
    print(
        "  plane   h       nodes  ratio  lattice  mode          3-D MC   diff     in-plane  Kupfer"
    )
    for plane in ("stress", "strain"):
        for h in hs:
            for ratio in RATIOS:
                r = first_failure(h, plane, ratio)
                rows.append(r)
                lat, ref = r["lattice"], r["mohr_coulomb_3d"]
                diff = "" if lat is None or not np.isfinite(ref) else f"{lat / ref - 1:+.2%}"
                print(
                    f"  {plane:6s} {h:6.3f} {r['nodes']:7d} {ratio:6.2f}  {_fmt(lat):7s}  "
                    f"{str(r['mode']):12s}  {_fmt(ref):7s}  {diff:7s}  "
                    f"{_fmt(r['in_plane_only']):8s}  {_fmt(r['kupfer'], '-')}"
                )
    return rows


def main(argv=None) -> int:
    args = parser(__doc__).parse_args(argv)
    hs = (0.08,) if args.quick else (0.05, 0.025)
    print("biaxial strength, first failure p / fc (sigma_xx = ratio sigma_yy)")
    rows = table(hs)
    worst = max(
        abs(r["lattice"] / r["mohr_coulomb_3d"] - 1)
        for r in rows
        if r["lattice"] is not None and np.isfinite(r["mohr_coulomb_3d"])
    )
    never = all((r["lattice"] is None) == (not np.isfinite(r["mohr_coulomb_3d"])) for r in rows)
    print(
        f"  largest difference from the 3-D envelope {worst:.2%}; "
        f"never-failing states agree: {never}"
    )
    data = {
        "rows": rows,
        "worst_vs_3d": worst,
        "never_agrees": never,
        "fc": FC,
        "ft": FT,
        "phi": PHI,
    }
    print("wrote", write_json(data, args.out / "biaxial.json"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
