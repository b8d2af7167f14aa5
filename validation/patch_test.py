"""Uniform and Lame stress states on a ring: the lattice's surface layer on curved
boundaries (issues 24 and 28).

A ring a = 0.5, b = 1 (plane strain, E = 1e4, nu = 0.3), held by three point supports,
under three loadings with closed-form displacements:

* ``hydrostatic``: pressure 1 on both circles, a uniform stress (u = -(1 - nu*) r / E*);
* ``deviatoric``: pressures 2 G B / a^2 and 2 G B / b^2, the pure-shear Lame field
  u_r = B / r (no volume change, no dependence on nu);
* ``lame``: pressure 1 on the bore only.

For each the relative L2 error of the displacement at the nodes (rigid motion taken out)
is printed for the plain lattice (``boundary_cells="lattice"``) with ``bonds="surface"``,
``"fabric"`` (the surface springs with the local anisotropy of the cells taken out) and
``"voronoi"``, and for the default (``"exact cells"``: the triangles at the boundary
carry the isotropic tensor, :mod:`dvstatic.lattice.cells`), on the package's jittered,
CVT and random meshes at two spacings. A continuum passes the
first test exactly on any mesh (so does P1); a lattice whose surface layer is right
should too, up to its interior fluctuation.

Usage::

    python validation/patch_test.py           # h = 0.04 and 0.02 (about 2e3 and 7e3 nodes)
    python validation/patch_test.py --quick   # h = 0.04

Writes ``validation/out/patch_test.json`` (``--quick``: ``validation/out/quick/``).
"""

from __future__ import annotations

import numpy as np
from _common import parser, write_json

import dvstatic as dv
from dvstatic.fem.compare import _without_rigid

E, NU, A, B = 1e4, 0.3, 0.5, 1.0
E_S, NU_S = E / (1 - NU**2), NU / (1 - NU)  # plane strain: the in-plane constants
G = E_S / (2 * (1 + NU_S))
SHEAR = 1e-4  # B of the deviatoric field


def ring(kind: str, h: float) -> dv.Mesh:
    hole = dv.mesh.Circle((0.0, 0.0), A, name="bore")
    return dv.mesh.disc(B, h, holes=[hole], kind=kind, seed=1)


def cases(r: np.ndarray) -> dict:
    """Loads and exact radial displacement of the three states."""
    return {
        "hydrostatic": (
            [dv.Pressure("bore", 1.0), dv.Pressure("boundary", 1.0)],
            -(1 - NU_S) / E_S * r,
        ),
        "deviatoric": (
            [dv.Pressure("bore", 2 * G * SHEAR / A**2), dv.Pressure("boundary", 2 * G * SHEAR)],
            SHEAR / r,
        ),
        "lame": (
            [dv.Pressure("bore", 1.0)],
            (1 + NU) * A**2 / (E * (B**2 - A**2)) * ((1 - 2 * NU) * r + B**2 / r),
        ),
    }


def errors(mesh: dv.Mesh, solve) -> dict:
    near = [int(np.argmin(np.hypot(*(mesh.points - q).T))) for q in ((B, 0), (-B, 0), (0, B))]
    sup = [
        dv.Fix(np.array([near[0]]), y=0.0),
        dv.Fix(np.array([near[1]]), y=0.0),
        dv.Fix(np.array([near[2]]), x=0.0),
    ]
    r = np.hypot(*mesh.points.T)
    out = {}
    for name, (loads, ur) in cases(r).items():
        exact = mesh.points * (ur / r)[:, None]
        d, _ = _without_rigid(mesh.points, solve(sup, loads) - exact)
        out[name] = float(np.linalg.norm(d) / np.linalg.norm(exact))
    return out


def main(argv=None) -> int:
    args = parser(__doc__).parse_args(argv)
    rows = []
    for kind in ("jittered", "cvt", "random"):
        for h in (0.04,) if args.quick else (0.04, 0.02):
            mesh = ring(kind, h)
            p1 = errors(
                mesh,
                lambda s, f, m=mesh: dv.fem.solve(m, E, NU, s, f, order=1, plane="strain").u,
            )
            rows.append({"mesh": kind, "h": h, "nodes": mesh.n_points, "model": "P1", **p1})
            for bonds in ("surface", "fabric", "voronoi", "exact cells"):
                cells = "exact" if bonds == "exact cells" else "lattice"
                model = dv.DV(
                    mesh,
                    E,
                    NU,
                    plane="strain",
                    bonds="auto" if cells == "exact" else bonds,
                    boundary_cells=cells,
                )
                e = errors(mesh, lambda s, f, m=model: dv.solve(m, s, f).u)
                rows.append({"mesh": kind, "h": h, "nodes": mesh.n_points, "model": bonds, **e})
            for r in rows[-5:]:
                print(
                    f"{r['mesh']:9s} h {r['h']:.2f} {r['nodes']:6d} nodes {r['model']:8s} "
                    f"hydrostatic {100 * r['hydrostatic']:6.2f} %  "
                    f"deviatoric {100 * r['deviatoric']:6.2f} %  lame {100 * r['lame']:6.2f} %",
                    flush=True,
                )
    out = write_json({"quick": args.quick, "rows": rows}, args.out / "patch_test.json")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
