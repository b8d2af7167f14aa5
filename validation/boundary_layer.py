"""Where a lattice's displacement error lives: the layer of triangles at the boundary.

A DV triangle is a P1 element with its own tensor ``C_T = E_T^T Q_T E_T / A`` (``E_T``
the elongations of its three bonds per unit strain, ``Q_T`` its springs and coupling):
the stiffness of every triangle is exactly P1's with ``C_T`` in place of the isotropic
``C`` (checked here to 1e-13). On a lattice or jittered mesh the interior tensors are
right (or calibrated right after relaxation); the triangles that touch the boundary are
cut to fit it and their tensors are not. This script measures how much of the lattice's
error they carry: the same problem solved (1) by the lattice, (2) by P1 FE on the same
triangles, (3) by the lattice with the triangles next to a hole replaced by P1 with the
isotropic ``C``, and (4) with every triangle that touches the boundary replaced so.
Errors are L2 norms of the nodal displacement against the exact field, near the hole
(r < 1.05 a), at 1.05-1.5 a and far (r > 2.5 a; the cantilever and Lame: whole body).

The lattice here is the plain one (``boundary_cells="lattice"``). With ``--stress``,
Kirsch's plate and the Lame quarter cylinder also run the package's own stress recovery
on the plain lattice and on the default, whose boundary triangles are exact cells
(``Q_T = A E_T^-T C E_T^-1``, exactly P1 with the isotropic C:
:mod:`dvstatic.lattice.cells`; this script's measurements were the reason for them).

``python validation/boundary_layer.py [--quick] [--stress]`` prints a table and writes
``boundary_layer.json``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from _benchmarks import cantilever, kirsch, lame
from _common import parser, write_json

import dvstatic as dv
from dvstatic.lattice import geometry as _geometry
from dvstatic.lattice.damage import split
from dvstatic.problem.problem import Problem


def _p1_matrices(x: np.ndarray, C: np.ndarray) -> np.ndarray:
    """P1 element matrices (m, 6, 6) of triangles ``x`` (m, 3, 2) with the Mandel tensor
    ``C`` (3, 3), or one per triangle (m, 3, 3)."""
    (x1, y1), (x2, y2), (x3, y3) = x[:, 0].T, x[:, 1].T, x[:, 2].T
    area = 0.5 * ((x2 - x1) * (y3 - y1) - (x3 - x1) * (y2 - y1))
    b = np.stack([y2 - y3, y3 - y1, y1 - y2], 1) / (2 * area)[:, None]
    c = np.stack([x3 - x2, x1 - x3, x2 - x1], 1) / (2 * area)[:, None]
    B = np.zeros((len(x), 3, 6))
    B[:, 0, 0::2], B[:, 1, 1::2] = b, c
    B[:, 2, 0::2], B[:, 2, 1::2] = c / np.sqrt(2), b / np.sqrt(2)
    C = np.broadcast_to(C, (len(x), 3, 3))
    return np.einsum("mki,mkl,mlj->mij", B, C, B) * np.abs(area)[:, None, None]


def elongations(s, mesh) -> tuple[np.ndarray, np.ndarray]:
    """The elongations of every triangle's bonds per unit strain ``E_T`` (m, 3 bonds,
    3 Mandel strains) from the split ``s``, and the triangles' areas (m,)."""
    x = mesh.points[mesh.triangles]
    unit = (np.diag([1.0, 0.0]), np.diag([0.0, 1.0]), np.array([[0, 1], [1, 0]]) / np.sqrt(2))
    e = np.stack([np.einsum("mkj,mj->mk", s.b, (x @ u.T).reshape(len(x), 6)) for u in unit], -1)
    return e, _geometry.of(mesh).tri_area


def triangle_tensors(s, mesh) -> np.ndarray:
    """Every triangle's own tensor ``C_T = E_T^T Q_T E_T / A`` (m, 3, 3), Mandel."""
    e, area = elongations(s, mesh)
    return np.einsum("mki,mkl,mlj->mij", e, s.q(s.w, s.g), e) / area[:, None, None]


def _iso(bm) -> np.ndarray:
    E, nu = bm.E, bm.nu
    if bm.plane == "strain":
        E, nu = E / (1 - nu**2), nu / (1 - nu)
    return E / (1 - nu**2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, 1 - nu]])


def _solve(K, pr) -> np.ndarray:
    n = K.shape[0]
    free = np.ones(n, dtype=bool)
    free[pr.dofs] = False
    u = np.zeros(n)
    u[pr.dofs] = pr.values
    u[free] = spla.spsolve(K[free][:, free].tocsc(), (pr.f - K @ u)[free])
    return u.reshape(-1, 2)


def row(name: str, bm, kind: str, nodes: int, hole: str | None) -> dict:
    mesh = bm.make_mesh(bm.h_for(nodes), kind=kind, seed=1)
    model = dv.DV(mesh, bm.E, bm.nu, plane=bm.plane, boundary_cells="lattice")
    sup, loads = bm.problem(mesh)
    pr = Problem.build(model, sup, loads)
    s = split(model)
    tri, p = mesh.triangles, mesh.points
    on_b = np.zeros(mesh.n_points, dtype=bool)
    on_b[np.unique(mesh.topology.boundary_edges)] = True
    layers = {"all boundary triangles": on_b[tri].any(axis=1)}
    if hole:
        on_h = np.zeros(mesh.n_points, dtype=bool)
        on_h[mesh.part_nodes(hole)] = True
        layers = {"hole triangles": on_h[tri].any(axis=1), **layers}
    K0 = s.stiffness(mesh, s.w, s.g).tocsr()
    # the identity the diagnosis rests on: each DV triangle is P1 with its own C_T
    ke_dv = np.einsum("mki,mkl,mlj->mij", s.b, s.q(s.w, s.g), s.b)
    ke_p1 = _p1_matrices(p[tri], triangle_tensors(s, mesh))
    identity = float(np.abs(ke_dv - ke_p1).max() / np.abs(ke_dv).max())
    ue = bm.exact(p)
    r = np.hypot(*p.T)
    zones = (
        {"near": r < 1.05, "mid": (r >= 1.05) & (r < 1.5), "far": r > 2.5}
        if name == "kirsch"
        else {"whole": np.ones(len(p), dtype=bool)}
    )

    def errors(u):
        return {
            z: float(np.linalg.norm(u[m] - ue[m]) / np.linalg.norm(ue[m])) for z, m in zones.items()
        }

    fe = dv.fem.solve(model, sup, loads, order=1)
    out = {
        "problem": name,
        "kind": kind,
        "nodes": mesh.n_points,
        "dv_is_p1_with_C_T": identity,
        "lattice": errors(_solve(K0, pr)),
        "P1": errors(fe.u.reshape(-1, 2)),
    }
    C = _iso(bm)
    for label, layer in layers.items():
        w, g = s.w.copy(), s.g.copy()
        w[layer], g[layer] = 0.0, 0.0
        ke = _p1_matrices(p[tri[layer]], C)
        dofs = np.stack([2 * tri[layer], 2 * tri[layer] + 1], -1).reshape(-1, 6)
        rows, cols = np.repeat(dofs, 6, 1).ravel(), np.tile(dofs, (1, 6)).ravel()
        K = s.stiffness(mesh, w, g).tocsr() + sp.csr_matrix((ke.ravel(), (rows, cols)), K0.shape)
        out[label] = errors(_solve(K, pr)) | {"triangles": int(layer.sum())}
    return out


def stress_row(name: str, bm, kind: str, nodes: int, hole: str) -> dict:
    """Hoop stress along the hole (recovered) and displacement: the plain lattice
    against the package's exact boundary cells (the default)."""
    mesh = bm.make_mesh(bm.h_for(nodes), kind=kind, seed=1)
    p = mesh.points
    hn = mesh.part_nodes(hole)
    th = np.arctan2(p[hn, 1], p[hn, 0])
    c, sn = np.cos(th), np.sin(th)

    def hoop(t):
        return t[:, 0, 0] * sn * sn + t[:, 1, 1] * c * c - 2 * t[:, 0, 1] * sn * c

    exact = hoop(bm.stress_exact(p[hn]))
    ue = bm.exact(p)
    out = {"problem": name, "kind": kind, "nodes": mesh.n_points}
    for label, cells in (("lattice", "lattice"), ("exact boundary cells", "exact")):
        model = dv.DV(mesh, bm.E, bm.nu, plane=bm.plane, boundary_cells=cells)
        out["cells"] = max(out.get("cells", 0), int(len(model.cell_triangles)))
        sol = dv.solve(model, *bm.problem(mesh))
        rel = (hoop(sol.stress()[hn]) - exact) / np.abs(exact).max()
        u = sol.u.reshape(-1, 2)
        top = int(np.argmax(th))
        out[label] = {
            "l2": float(np.linalg.norm(u - ue) / np.linalg.norm(ue)),
            "hoop_rms": float(np.sqrt(np.mean(rel**2))),
            "hoop_worst": float(np.abs(rel).max()),
            "hoop_at_top": float(rel[top] * np.abs(exact).max() / exact[top]),
        }
    return out


def main(argv=None) -> int:
    p = parser(__doc__)
    p.add_argument("--stress", action="store_true", help="also the recovered stresses")
    args = p.parse_args(argv)
    sizes = (5000,) if args.quick else (5000, 20000, 80000)
    cases = [
        ("kirsch", kirsch(0.3), "hole"),
        ("lame", lame(), "bore"),
        ("cantilever", cantilever(), None),
    ]
    rows = []
    for name, bm, hole in cases:
        for kind in ("lattice", "jittered"):
            for n in sizes if name == "kirsch" else sizes[:2]:
                r = row(name, bm, kind, n, hole)
                rows.append(r)
                cells = "  ".join(
                    f"{k}: " + "/".join(f"{v:.4f}" for z, v in r[k].items() if z != "triangles")
                    for k in r
                    if isinstance(r[k], dict)
                )
                print(f"{name:10s} {kind:8s} {r['nodes']:6d}  {cells}", flush=True)
    stress = []
    if args.stress:
        for name, bm, hole in cases[:2]:
            for kind in ("lattice", "jittered", "cvt"):
                for n in sizes if name == "kirsch" else sizes[1:2]:
                    r = stress_row(name, bm, kind, n, hole)
                    stress.append(r)
                    cells = "  ".join(
                        f"{k}: L2 {r[k]['l2']:.4f} hoop rms {r[k]['hoop_rms']:.4f} worst "
                        f"{r[k]['hoop_worst']:.4f} top {r[k]['hoop_at_top']:+.4f}"
                        for k in ("lattice", "exact boundary cells")
                    )
                    print(f"{name:10s} {kind:8s} {r['nodes']:6d}  {cells}", flush=True)
    write_json({"rows": rows, "stress": stress}, args.out / "boundary_layer.json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
