"""Fracture in compression (dv.fracture with criterion "mohr-coulomb", held loads):
uniaxial compression of a 1 x 2 prism between frictionless platens on CVT meshes,
the emergent strength for three (c, phi) pairs, biaxial compression under a held
lateral pressure (the Coulomb slope), and the Brazilian disc with the Mohr-Coulomb
criterion. Prints tables, writes compression.json and compression.png.

Prism: E = 2e4, nu = 0.2, ft = 2, c = 6, phi = 30 deg (the continuum's UCS =
2 c cos(phi) / (1 - sin(phi)) = 20.78), displacement control (the top platen moves
down), brittle bonds. The load is the platen force over the width: the axial stress.
Biaxial: the lateral pressure p = 0, 0.1, 0.2, 0.4 UCS is held at full value in every
state (dv.fracture(..., held=[...])), in plane strain (sigma_zz = nu (sigma_xx +
sigma_yy) confines the prism out of its plane too); the envelope says sigma_1 = UCS + p
(1 + sin phi) / (1 - sin phi). (In plane stress a held lateral pressure does not
strengthen the prism: it fails out of plane at the UCS, validation/biaxial.py.) Every
recorded state is re-solved from scratch to check that it is in
equilibrium with the held pressure at full value.
"""

from __future__ import annotations

import time

import numpy as np
from _common import parser, write_json
from fracture import brazilian

import dvstatic as dv
from dvstatic.crack import ucs
from dvstatic.lattice.damage import split
from dvstatic.linalg import ConstrainedSystem
from dvstatic.problem import constraints, load_vector

E, NU, FT, C, PHI = 2e4, 0.2, 2.0, 6.0, 30.0


def platens(mesh, d: float = 1e-3):
    """Frictionless platens: the bottom fixed, the top moved down by ``d``, the bottom
    node nearest the middle held sideways."""
    mid = int(np.argmin(np.hypot(mesh.points[:, 0] - 0.5, mesh.points[:, 1])))
    return [dv.Fix("bottom", y=0.0), dv.Fix("top", y=-d), dv.Fix([mid], x=0.0)]


def prism_run(
    h: float, c=C, phi=PHI, p=0.0, seed=1, max_events=4000, per_node=None, plane="stress", **kw
):
    """One prism: the result, the largest equilibrium error of its snapshots, seconds
    (``per_node``: that many events per node instead of ``max_events``; ``kw`` more
    keywords of dv.fracture)."""
    mesh = dv.mesh.rectangle(1.0, 2.0, h, kind="cvt", seed=seed)
    model = dv.DV(mesh, E=E, nu=NU, plane=plane)
    held = [dv.Pressure("left", p), dv.Pressure("right", p)] if p else None
    t0 = time.perf_counter()
    res = dv.fracture(
        model,
        platens(mesh),
        None,
        held=held,
        ft=FT,
        criterion="mohr-coulomb",
        cohesion=c,
        friction_angle=phi,
        max_events=max_events if per_node is None else int(per_node * mesh.n_points),
        **{"stop_load_ratio": 0.05, **kw},
    )
    seconds = time.perf_counter() - t0
    return res, _held_equilibrium(model, res, held), seconds


def _held_equilibrium(model, res, held) -> float:
    """The largest relative residual ``|A u - b| / |b|`` of the constrained system of
    every snapshot (the damaged stiffness assembled afresh, ``b`` the held loads at full
    value and the growing loads and prescribed displacements at the event's load factor;
    0 without held loads)."""
    if not held:
        return 0.0
    mesh = model.mesh
    s = split(res.model)  # the lattice that broke (dv.fracture gives back exact cells)
    dofs, values = constraints(mesh, list(res.supports))
    fh = load_vector(mesh, list(held), thickness=model.t)
    f = load_vector(mesh, list(res.loads), thickness=model.t) if res.loads else 0.0 * fh
    worst = 0.0
    for snap in res.snapshots:
        lam = res.events[snap.event].load_factor
        k = s.stiffness(mesh, *s.factors(snap.stiffness, snap.closed))
        system = ConstrainedSystem(k, dofs)
        b = system.rhs(fh + lam * f, lam * values)
        r = system.A @ snap.u.ravel() - b
        worst = max(worst, float(np.linalg.norm(r) / np.linalg.norm(b)))
    return worst


def row(res, seconds, c=C, phi=PHI, p=0.0, eq=0.0) -> dict:
    strength = ucs(c, phi)
    k = (1 + np.sin(np.radians(phi))) / (1 - np.sin(np.radians(phi)))
    env = strength + k * p
    first, peak = res.events[0], res.peak
    return {
        "nodes": res.model.mesh.n_points,
        "c": c,
        "phi": phi,
        "p": p,
        "ucs": strength,
        "envelope": env,
        "first": first.load,
        "first_mode": first.mode,
        "peak": peak.load,
        "peak_event": peak.index,
        "peak_over_envelope": peak.load / env,
        "ucs_over_ft": peak.load / FT if p == 0 else None,
        "events": len(res.events),
        "broken": len(res.broken),
        "modes": res.to_dict()["modes"],
        "stop": res.stop_reason,
        "held_equilibrium": eq,
        "seconds": seconds,
    }


def uniaxial(hs) -> tuple[list, list]:
    rows, results = [], []
    print("uniaxial compression, c = 6, phi = 30 deg (UCS 20.78)")
    print("   nodes  first   mode      peak   peak/UCS events  tension shear crushing out-of-plane")
    for h in hs:
        res, _, s = prism_run(h)
        r = row(res, s)
        rows.append(r)
        results.append(res)
        m = r["modes"]
        print(
            f"  {r['nodes']:6d} {r['first']:6.2f}  {r['first_mode']:8s} {r['peak']:6.2f}  "
            f"{r['peak_over_envelope']:7.3f}  {r['events']:5d}  {m['tension']:6d} "
            f"{m['shear']:5d} {m['crushing']:7d} {m['out-of-plane']:7d}   ({s:.1f} s)"
        )
    return rows, results


#: the prism's mode I fracture energy in the softening study (energy per area; about 20 x
#: the smallest the finer mesh admits)
GF_PRISM = 1e-3


def softening(hs) -> tuple[list, list]:
    """The prism with tension softening (gf) and faces failing in shear or crushing
    brittle (gf_shear = 0), at the default gf_shear = 10 gf and at 30 gf; the default
    on both meshes, each for the same number of events per node. Per run: the peak, the
    load envelope at the end (the largest load of the last 10 % of the events: single
    events far below it are SLA's snap-backs, mostly corner bonds cracking in tension),
    the platen displacement and energy dissipated by then, and what the lattice released
    through the faces that failed in shear or crushing and went through all their
    teeth, against their gf_shear share."""
    from dvstatic.crack.energies import BUFFON, GF_SHEAR_RATIO, face_of

    runs = [(hs[0], 0.0), (hs[0], None), (hs[0], 3 * GF_SHEAR_RATIO * GF_PRISM)]
    runs += [(h, None) for h in hs[1:]]
    rows, results = [], []
    print(f"softening: uniaxial compression with gf = {GF_PRISM:g} (UCS 20.78)")
    print(
        "   nodes  gf_shear   peak/UCS  at event  events  end/UCS  end displ.  dissipated  "
        "shear faces released"
    )
    for h, gfs in runs:
        kw = dict(gf=GF_PRISM, gf_shear=gfs, stop_load_ratio=0.0)
        res, _, seconds = prism_run(h, per_node=2.5, **kw)
        model, mesh = res.model, res.model.mesh
        tail = res.events[-max(1, len(res.events) // 10) :]
        value = GF_SHEAR_RATIO * GF_PRISM if gfs is None else gfs
        released, first = {}, {}
        for ev in res.events:
            released[ev.bond] = released.get(ev.bond, 0.0) + ev.released
            first.setdefault(ev.bond, ev)
        target = BUFFON * value * face_of(model) * model.t
        through = [
            released[b] / target[b]
            for b in res.broken
            if first[b].mode != "tension" and not first[b].broken
        ]
        r = {
            "nodes": mesh.n_points,
            "gf": GF_PRISM,
            "gf_shear": value,
            "peak_over_ucs": res.peak.load / ucs(C, PHI),
            "peak_event": res.peak.index,
            "events": len(res.events),
            "end_over_ucs": max(ev.load for ev in tail) / ucs(C, PHI),
            "end_displacement": res.events[-1].control_displacement,
            "dissipated": res.dissipated,
            "modes": res.to_dict()["modes"],
            "shear_faces_through_teeth": len(through),
            "shear_released_over_share_median": float(np.median(through)) if through else None,
            "stop": res.stop_reason,
            "seconds": seconds,
        }
        rows.append(r)
        results.append(res)
        share = r["shear_released_over_share_median"]
        print(
            f"  {r['nodes']:6d}  {value:8.2g}  {r['peak_over_ucs']:8.3f}  {r['peak_event']:8d}  "
            f"{r['events']:6d}  {r['end_over_ucs']:7.3f}  {r['end_displacement']:10.3e}  "
            f"{r['dissipated']:10.3e}  "
            + (f"{share:.3f} of gf_shear ({len(through)} faces)" if through else "-")
            + f"   ({seconds:.0f} s, {r['stop']})"
        )
    return rows, results


def plot_softening(rows, results, path) -> None:
    """Load against platen displacement (SLA's snap-backs and all) and the load envelope
    against events per node."""
    from dvstatic import plot as dvplot

    fig, axes = dvplot.figure(2, 1, (11.0, 4.5))
    for r, res in zip(rows, results, strict=True):
        d, p = res.curve()
        label = f"{r['nodes']} nodes, gf_shear = {r['gf_shear']:g}"
        axes[0][0].plot(d, p, lw=0.4, label=label)
        load = np.array([ev.load for ev in res.events])
        window = max(1, len(load) // 100)
        top = _running_max(load, window)
        axes[0][1].plot(np.arange(len(load)) / r["nodes"], top / ucs(C, PHI), lw=0.8, label=label)
    for ax in axes[0]:
        ax.legend(fontsize=7)
    axes[0][0].axhline(ucs(C, PHI), color="k", ls="--", lw=0.8)
    axes[0][0].set_xlabel("platen displacement")
    axes[0][0].set_ylabel("axial stress")
    axes[0][0].set_title(f"uniaxial compression, gf = {GF_PRISM:g}", fontsize=9)
    axes[0][1].set_xlabel("events per node")
    axes[0][1].set_ylabel("load envelope / UCS (largest over 1 % of the events)")
    print("wrote", dvplot.save(fig, path))


def _running_max(values: np.ndarray, window: int) -> np.ndarray:
    """The largest of each run of ``window`` values, at every value's position."""
    from scipy.ndimage import maximum_filter1d

    return maximum_filter1d(values, size=window, mode="nearest")


def pairs(h) -> list:
    out = []
    print("emergent strength for three (c, phi) pairs")
    print("      c   phi    UCS   peak  peak/UCS  peak/ft")
    for c, phi in ((6.0, 30.0), (4.0, 40.0), (10.0, 20.0)):
        res, _, s = prism_run(h, c, phi)
        r = row(res, s, c, phi)
        out.append(r)
        print(
            f"  {c:5.1f} {phi:5.1f} {r['ucs']:6.2f} {r['peak']:6.2f}  "
            f"{r['peak_over_envelope']:7.3f}  {r['ucs_over_ft']:6.2f}"
        )
    return out


def biaxial(h) -> dict:
    strength = ucs(C, PHI)
    rows = []
    print("biaxial compression, held lateral pressure p (plane strain)")
    print("   p/UCS     p   envelope   first    peak  peak/env  held equilibrium")
    for frac in (0.0, 0.1, 0.2, 0.4):
        p = frac * strength
        res, eq, s = prism_run(h, p=p, plane="strain")
        r = row(res, s, p=p, eq=eq)
        rows.append(r)
        print(
            f"  {frac:5.2f} {p:6.2f} {r['envelope']:8.2f} {r['first']:7.2f} {r['peak']:7.2f}  "
            f"{r['peak_over_envelope']:7.3f}   {eq:.1e}"
        )
    p = np.array([r["p"] for r in rows])
    slope_peak = float(np.polyfit(p, [r["peak"] for r in rows], 1)[0])
    slope_first = float(np.polyfit(p, [r["first"] for r in rows], 1)[0])
    k = (1 + np.sin(np.radians(PHI))) / (1 - np.sin(np.radians(PHI)))
    print(
        f"  slope of sigma_1 against p: peak {slope_peak:.3f}, first failure {slope_first:.3f} "
        f"(Mohr-Coulomb {k:.3f})"
    )
    return {"rows": rows, "slope_peak": slope_peak, "slope_first": slope_first, "slope_mc": k}


# ------------------------------------------------------------------ tunnel
TUNNEL = dict(L=8.0, E=1e4, nu=0.25, ft=1.0, c=3.0, phi=30.0)


def tunnel_model(h_near: float, L: float = TUNNEL["L"]):
    """A square block 2L x 2L with a circular tunnel of radius 1 at its centre (CVT,
    graded from h_near at the wall to 0.6)."""

    def size(x):
        r = np.hypot(x[:, 0] - L, x[:, 1] - L)
        return np.minimum(0.6, h_near + 0.12 * np.maximum(r - 1.0, 0.0))

    hole = dv.domain.Circle((L, L), 1.0, name="tunnel")
    mesh = dv.mesh.rectangle(2 * L, 2 * L, size, kind="cvt", seed=1, holes=[hole])
    model = dv.DV(mesh, E=TUNNEL["E"], nu=TUNNEL["nu"])

    def near(p):
        return int(np.argmin(np.hypot(*(mesh.points - np.asarray(p)).T)))

    sup = [
        dv.Fix([near((2 * L, L))], y=0.0),
        dv.Fix([near((0.0, L))], y=0.0),
        dv.Fix([near((L, 2 * L))], x=0.0),
    ]
    return model, sup


def in_situ(K: float, p: float = 1.0):
    """Far-field stresses sigma_v = -p, sigma_h = -K p as tractions on the block."""
    return [
        dv.Traction("top", (0.0, -p)),
        dv.Traction("bottom", (0.0, p)),
        dv.Traction("left", (K * p, 0.0)),
        dv.Traction("right", (-K * p, 0.0)),
    ]


def _kirsch_onset(K: float) -> tuple[float, str]:
    """The in-situ stress p at which the wall first fails in an infinite medium: the
    crown's hoop tension (1 - 3 K) p against ft, or the sidewall's uniaxial hoop
    compression (3 - K) p against the UCS."""
    t = TUNNEL
    tension = t["ft"] / (1 - 3 * K) if K < 1 / 3 else np.inf
    crush = ucs(t["c"], t["phi"]) / (3 - K)
    return (
        (tension, "tension at the crown") if tension < crush else (crush, "crushing at the walls")
    )


def tunnel_onset(K: float, h_near: float, L: float = TUNNEL["L"]) -> dict:
    """Where and at what in-situ stress the first face fails, against Kirsch and against
    P2 FE on the same block (its wall stresses put into the same envelope)."""
    t = TUNNEL
    model, sup = tunnel_model(h_near, L)
    loads = in_situ(K)
    kw = dict(criterion="mohr-coulomb", cohesion=t["c"], friction_angle=t["phi"])
    res = dv.fracture(model, sup, loads, ft=t["ft"], max_events=1, **kw)
    ev = res.events[0]
    mesh = model.mesh
    mid = mesh.points[mesh.topology.bonds[ev.bond]].mean(axis=0) - L
    fe = dv.fem.solve(mesh, t["E"], t["nu"], sup, loads, order=2, refine=1)
    crown = fe.stress([[L, L + 1.0]])[0][0, 0]
    wall = fe.stress([[L + 1.0, L]])[0][1, 1]
    fe_p = min(t["ft"] / crown if crown > 0 else np.inf, ucs(t["c"], t["phi"]) / -wall)
    kirsch, where = _kirsch_onset(K)
    out = {
        "K": K,
        "block": 2 * L,
        "h_near": h_near,
        "nodes": mesh.n_points,
        "p_first": ev.load_factor,
        "mode": ev.mode,
        "theta_deg": float(np.degrees(np.arctan2(mid[1], mid[0]))),
        "r": float(np.hypot(*mid)),
        "p_kirsch": kirsch,
        "kirsch_where": where,
        "p_fe": fe_p,
        "fe_crown_hoop": crown,
        "fe_wall_hoop": wall,
    }
    print(
        f"  K = {K:g} ({out['nodes']} nodes): first failure at p = {ev.load_factor:.3f} "
        f"({ev.mode}, theta = {out['theta_deg']:.0f} deg, r = {out['r']:.3f}); Kirsch "
        f"{kirsch:.3f} ({where}; {ev.load_factor / kirsch - 1:+.1%}); P2 FE on the same "
        f"block {fe_p:.3f} ({ev.load_factor / fe_p - 1:+.1%})"
    )
    return out


def convergence_confinement(p0_over_ucs: float, h_near: float) -> dict:
    """K = 1: the in-situ stress p0 and a support pressure p0 in the tunnel held; the
    support pressure released by the load factor (lambda = 1: a free wall). Lame: the
    wall fails when (1 + lambda) p0 = UCS + k (1 - lambda) p0 in the plane; in plane
    stress sigma_zz = 0 is the largest principal stress, so out of the plane it fails
    first, when (1 + lambda) p0 = UCS (``lambda_3d``)."""
    t = TUNNEL
    strength = ucs(t["c"], t["phi"])
    p0 = p0_over_ucs * strength
    k = (1 + np.sin(np.radians(t["phi"]))) / (1 - np.sin(np.radians(t["phi"])))
    model, sup = tunnel_model(h_near)
    held = [*in_situ(1.0, p0), dv.Pressure("tunnel", p0)]
    kw = dict(criterion="mohr-coulomb", cohesion=t["c"], friction_angle=t["phi"])
    res = dv.fracture(
        model,
        sup,
        [dv.Pressure("tunnel", -p0)],
        held=held,
        ft=t["ft"],
        max_events=400,
        stop_load_ratio=0.0,
        **kw,
    )
    lam = np.array([e.load_factor for e in res.events])
    lame = (strength + (k - 1) * p0) / ((1 + k) * p0)
    lame_3d = min(lame, strength / p0 - 1.0)
    out = {
        "p0": p0,
        "nodes": model.mesh.n_points,
        "lambda_first": float(lam[0]),
        "lambda_lame": float(lame),
        "lambda_3d": float(lame_3d),
        "mode_first": res.events[0].mode,
        "events": len(res.events),
        "events_below_full_release": int(np.sum(lam <= 1.0)),
        "stop": res.stop_reason,
        "held_equilibrium": _held_equilibrium(model, res, held),
    }
    print(
        f"  released support, K = 1, p0 = {p0_over_ucs:g} UCS: first failure at lambda = "
        f"{lam[0]:.3f} ({res.events[0].mode}; Lame in the plane {lame:.3f}, with sigma_zz "
        f"{lame_3d:.3f}, {lam[0] / lame_3d - 1:+.1%}); "
        f"{out['events_below_full_release']} of {len(lam)} events at lambda <= 1; held "
        f"equilibrium {out['held_equilibrium']:.1e}; stopped: {res.message}"
    )
    return out, res


#: unit weight of the beam (force per area): its own weight alone stresses the bottom
#: fibre at midspan to about 0.2 ft
GAMMA = 0.1


def beam_self_weight(h: float) -> dict:
    """A beam 4 x 0.5 on two bearing pads 0.1 long (span 3.7) under its own weight (held)
    and a growing point load at midspan (criterion stress): the held weight in every
    state."""
    mesh = dv.mesh.rectangle(4.0, 0.5, h, kind="cvt", seed=2)
    model = dv.DV(mesh, E=3e4, nu=0.2)

    def near(p):
        return int(np.argmin(np.hypot(*(mesh.points - np.asarray(p)).T)))

    x = mesh.points
    bottom = np.abs(x[:, 1]) < 1e-12
    # pads 0.1 long, 0.1 in from the ends (a pad at a corner concentrates its reaction on
    # the corner's short bonds, which the held weight alone then breaks)
    pads = [np.flatnonzero(bottom & (np.abs(x[:, 0] - c) <= 0.05)) for c in (0.15, 3.85)]
    sup = [dv.Fix(pads[0], y=0.0), dv.Fix(pads[1], y=0.0), dv.Fix([near((0.15, 0.0))], x=0.0)]
    weight = [dv.BodyForce((0.0, -GAMMA))]
    load = [dv.PointLoad([near((2.0, 0.5))], (0.0, -1.0))]
    res = dv.fracture(
        model,
        sup,
        load,
        held=weight,
        ft=3.0,
        gf=2e-3,
        weibull=dv.Weibull(24, 0.1, seed=1),
        max_events=3000,
        stop_load_ratio=0.1,
    )
    mid = mesh.points[mesh.topology.bonds[res.broken]].mean(axis=1)
    out = {
        "nodes": mesh.n_points,
        "events": len(res.events),
        "peak_load": res.peak.load,
        "first_load": res.events[0].load,
        "held_equilibrium": _held_equilibrium(model, res, weight),
        "crack_x": [float(mid[:, 0].min()), float(mid[:, 0].max())] if len(mid) else None,
        "stop": res.stop_reason,
    }
    # the beam theory estimate of the first crack: bottom fibre stress at midspan
    # (q L^2 / 8 + P L / 4) / (b d^2 / 6) = ft
    # (span 3.7, overhangs 0.15: the weight's midspan moment q (S^2 / 8 - o^2 / 2))
    q, S, o, d = GAMMA * 0.5, 3.7, 0.15, 0.5
    out["first_load_beam_theory"] = (3.0 * d**2 / 6 - q * (S**2 / 8 - o**2 / 2)) / (S / 4)
    print(
        f"  beam under held self-weight ({out['nodes']} nodes): first crack at P = "
        f"{out['first_load']:.4f} (beam theory {out['first_load_beam_theory']:.4f}), peak "
        f"{out['peak_load']:.4f}, {len(res.broken)} bonds broken at x in "
        f"{out['crack_x']}, held equilibrium {out['held_equilibrium']:.1e} ({out['stop']})"
    )
    return out, res


def brazilian_mc(h: float, ratio: float = 20.0) -> dict:
    """The Brazilian disc (fracture.py's set-up, ft = 3) with Mohr-Coulomb, c such that
    UCS = ``ratio`` ft (phi = 30 deg). In plane stress the strips' contact pressure is
    pi / 0.2 = 15.7 times the splitting stress, uniaxial out of the plane: with UCS = 10 ft
    the material under the strips crushes (out of plane) before the disc splits."""
    phi = 30.0
    c = ratio * 3.0 * (1 - np.sin(np.radians(phi))) / (2 * np.cos(np.radians(phi)))
    t0 = time.perf_counter()
    res, p_strip = brazilian(
        h,
        0,
        gf=5e-4,
        criterion="mohr-coulomb",
        cohesion=c,
        friction_angle=phi,
        max_events=6000,
        stop_load_ratio=0.3,
    )
    mesh = res.model.mesh
    mid = mesh.points[mesh.topology.bonds[res.broken]].mean(axis=1)
    out = {
        "nodes": mesh.n_points,
        "ucs_over_ft": ratio,
        "cohesion": c,
        "phi": phi,
        "splitting_over_ft": 2 * res.peak.load_factor * p_strip / (np.pi * 2.0) / 3.0,
        "near_diameter": float(np.mean(np.abs(mid[:, 0]) < 0.2)) if len(mid) else 0.0,
        "modes": res.to_dict()["modes"],
        "events": len(res.events),
        "seconds": time.perf_counter() - t0,
    }
    print(
        f"Brazilian disc, Mohr-Coulomb (c = {c:.2f}, phi = 30, UCS = {ratio:g} ft; "
        f"{out['nodes']} nodes): 2P/(pi D t) at the peak {out['splitting_over_ft']:.3f} ft, "
        f"{100 * out['near_diameter']:.0f} % of broken bonds within 0.1 D of the diameter, "
        f"modes {out['modes']}"
    )
    return out, res


def plot(results, bz, path) -> None:
    from matplotlib.collections import LineCollection

    from dvstatic import plot as dvplot
    from dvstatic.pictures import crack_faces

    fig, axes = dvplot.figure(len(results) + 2, 1, (4.0 * (len(results) + 2), 5.5))
    for ax, res in zip(axes[0], results, strict=False):
        mesh = res.model.mesh
        x = mesh.points
        ax.add_collection(LineCollection(x[mesh.boundary_edges], colors="k", linewidths=0.8))
        faces = crack_faces(res)[0]
        modes = {e.bond: e.mode for e in res.events}
        colour = {
            "tension": "tab:blue",
            "shear": "tab:green",
            "crushing": "tab:red",
            "out-of-plane": "tab:purple",
        }
        ax.add_collection(
            LineCollection(
                faces, colors=[colour[modes[int(b)]] for b in res.broken], linewidths=1.2
            )
        )
        ax.set_aspect("equal")
        ax.autoscale()
        ax.set_title(f"{mesh.n_points} nodes: blue tension, green shear, red crushing", fontsize=8)
    ax = axes[0][len(results)]
    for res in results:
        d, p = res.curve()
        ax.plot(d, p, ".", ms=2, label=f"{res.model.mesh.n_points} nodes")
    ax.axhline(ucs(C, PHI), color="k", ls="--", lw=0.8, label="Mohr-Coulomb UCS")
    ax.set_xlabel("platen displacement")
    ax.set_ylabel("axial stress")
    ax.legend(fontsize=7)
    ax = axes[0][len(results) + 1]
    rows = bz["rows"]
    p = [r["p"] for r in rows]
    ax.plot(p, [r["peak"] for r in rows], "o", label="lattice peak")
    ax.plot(p, [r["first"] for r in rows], "x", label="first failure")
    pp = np.linspace(0, max(p), 20)
    ax.plot(pp, ucs(C, PHI) + bz["slope_mc"] * pp, "k--", lw=0.8, label="Mohr-Coulomb")
    ax.set_xlabel("held lateral pressure p")
    ax.set_ylabel("sigma_1 at failure")
    ax.legend(fontsize=7)
    print("wrote", dvplot.save(fig, path))


def main(argv=None) -> int:
    args = parser(__doc__).parse_args(argv)
    hs = (0.06,) if args.quick else (0.04, 0.02)
    data = {}
    data["uniaxial"], results = uniaxial(hs)
    data["pairs"] = pairs(hs[0])
    data["softening"], soft = softening(hs)
    plot_softening(data["softening"], soft, args.out / "compression_softening.png")
    data["biaxial"] = biaxial(hs[0])
    data["brazilian"], _ = brazilian_mc(0.08 if args.quick else 0.04)
    data["brazilian_ucs10"], _ = brazilian_mc(0.08 if args.quick else 0.04, 10.0)
    h_near = 0.08 if args.quick else 0.04
    print("tunnel under in-situ stress (square block 16 x 16, radius 1)")
    data["tunnel"] = [tunnel_onset(K, h_near) for K in (0.2, 1.0)]
    if not args.quick:  # a block whose FE wall stresses are within 3 % of Kirsch's
        print("tunnel in a 40 x 40 block, the wall refined twice")
        data["tunnel_large"] = [
            tunnel_onset(K, h, 20.0) for K in (0.2, 1.0) for h in (0.04, 0.02, 0.01)
        ]
    data["convergence_confinement"], _ = convergence_confinement(0.6, h_near)
    data["beam_self_weight"], beam = beam_self_weight(0.08 if args.quick else 0.04)
    plot(results, data["biaxial"], args.out / "compression.png")
    from dvstatic.pictures import write_crack_png

    print("wrote", write_crack_png(args.out / "beam_self_weight.png", beam, "beam, held weight"))
    print("wrote", write_json(data, args.out / "compression.json"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
