"""An independent reference for the notched three-point-bending beam: Hillerborg's
fictitious (cohesive) crack model with a linear softening law on the known crack path
(the midspan ligament), on a P2 finite-element half beam (scikit-fem).

The elastic half beam is condensed onto the ligament points (every P2 node on it, one
solve per point); the
cohesive problem is then solved by crack-tip control, as Petersson (1981) did: for the
tip at ligament node m, the nodes below it follow ``sigma(w) = ft (1 - w / w_c)`` (or are
traction free beyond ``w_c = 2 Gf / ft``), the nodes above are closed, and the tip node
carries exactly ``ft``; that linear system gives the load and the deflection.
"""

from __future__ import annotations

import numpy as np

import dvstatic as dv


def _compliance(L, D, a, E, nu, t, h_near, h_far, spacing):
    import scipy.sparse.linalg as spla
    import skfem
    from skfem.models.elasticity import linear_elasticity

    from dvstatic.fem import build

    x0 = L / 2

    def size(p):
        return np.clip(h_near + 0.15 * np.abs(p[:, 0] - x0), h_near, h_far)

    mesh = dv.mesh.polygon([(0, 0), (x0, 0), (x0, D), (0, D)], size, kind="cvt")
    fe = build(mesh, 0, 2)
    basis = skfem.Basis(fe.skfem, skfem.ElementVector(skfem.ElementTriP2()))
    lam = E * nu / (1 - nu**2)
    mu = E / (2 * (1 + nu))
    K = t * skfem.asm(linear_elasticity(lam, mu), basis)  # plane stress: lam = E nu / (1 - nu^2)
    # every x dof on the ligament (P2: vertices and mid-edge nodes), bottom to top
    xdof = basis.nodal_dofs[0]
    xdofs = np.r_[xdof, basis.facet_dofs[0]] if basis.facet_dofs.size else xdof
    loc = basis.doflocs[:, xdofs].T
    on = np.flatnonzero(np.isclose(loc[:, 0], x0) & (loc[:, 1] >= a - 1e-9))
    on = on[np.argsort(loc[on, 1])]
    lig_x = xdofs[on]
    y_all = loc[on, 1]
    # the top point carries the load; it and the point below it are held in x (they stay
    # in compression): with the support's y that removes the three rigid motions
    top_y = basis.nodal_dofs[1][int(np.argmin(np.hypot(*(mesh.points - [x0, D]).T)))]
    corner = int(np.argmin(np.hypot(mesh.points[:, 0], mesh.points[:, 1])))
    D_ = np.array([basis.nodal_dofs[1, corner], lig_x[-1], lig_x[-2]])
    free = np.setdiff1d(np.arange(basis.N), D_)
    lu = spla.splu(K[free][:, free].tocsc())
    lig = lig_x[:-2]
    rhs = np.zeros((basis.N, len(lig) + 1))
    rhs[lig, np.arange(len(lig))] = 1.0  # unit +x (closing) force per point
    rhs[top_y, -1] = -1.0  # unit downward load at the top
    sol = np.zeros_like(rhs)
    sol[free] = lu.solve(rhs[free])
    ux = sol[lig]  # (n, n + 1)
    uy_top = sol[top_y]  # (n + 1,)
    y = y_all[:-2]
    edges = np.r_[a, 0.5 * (y[1:] + y[:-1]), 0.5 * (y[-1] + y_all[-2])]
    return ux, uy_top, y, np.diff(edges), mesh.n_points


def petersson_cohesive(
    L=2000.0, D=200.0, a=100.0, E=30000.0, nu=0.2, t=50.0, ft=3.33, gf=0.124, h_near=2.0, h_far=25.0
):
    """Load (N) and midspan deflection (mm) of the full beam, one point per tip position.

    Returns a dict with ``deflection``, ``load``, ``peak`` and the mesh size used.
    """
    ux, uy, y, b, n_nodes = _compliance(L, D, a, E, nu, t, h_near, h_far, h_near)
    n = len(y)
    f = ft * b * t  # force at the strength per node
    wc = 2 * gf / ft
    C, cq = ux[:, :n], ux[:, n]  # x displacement per unit closing force / unit half load
    loads, defl = [], []
    for m in range(n):
        open_ = np.zeros(n, dtype=bool)
        for _ in range(n + 1):
            A = np.zeros((n + 1, n + 1))
            r = np.zeros(n + 1)
            for i in range(n):
                if i < m and open_[i]:
                    A[i, i] = 1.0
                elif i < m:  # softening: F_i = f_i + (2 f_i / wc) u_x,i
                    A[i, :n] = -(2 * f[i] / wc) * C[i]
                    A[i, i] += 1.0
                    A[i, n] = -(2 * f[i] / wc) * cq[i] / 2
                    r[i] = f[i]
                else:  # closed: u_x,i = 0
                    A[i, :n] = C[i]
                    A[i, n] = cq[i] / 2
            A[n, m] = 1.0
            r[n] = f[m]
            z = np.linalg.solve(A, r)
            w = -2 * (C @ z[:n] + cq * z[n] / 2)
            now = (np.arange(n) < m) & (open_ | (w > wc))
            if np.array_equal(now, open_):
                break
            open_ = now
        P = z[n]
        loads.append(P)
        defl.append(-float(uy[:n] @ z[:n] + uy[n] * P / 2))
    loads, defl = np.array(loads), np.array(defl)
    k = int(np.argmax(loads))
    return {
        "deflection": defl.tolist(),
        "load": loads.tolist(),
        "peak_N": float(loads[k]),
        "peak_deflection": float(defl[k]),
        "ligament_nodes": n,
        "fe_nodes": n_nodes,
    }


if __name__ == "__main__":
    for hn in (4.0, 2.0):
        r = petersson_cohesive(h_near=hn)
        print(
            f"h_near {hn}: {r['ligament_nodes']} ligament nodes, {r['fe_nodes']} nodes: peak "
            f"{r['peak_N'] / 1e3:.4f} kN at {r['peak_deflection']:.4f} mm"
        )
