"""Equilibrated (Trefftz) fits of a displacement field: the stress at boundary nodes.

In a homogeneous isotropic body without body forces every plane displacement field
is given by two analytic functions (Kolosov-Muskhelishvili)::

    2 mu u = kappa phi(z) - z conj(phi'(z)) - conj(psi(z))
    sxx + syy = 4 Re phi'(z),     syy - sxx + 2 i sxy = 2 (conj(z) phi''(z) + psi'(z))

with ``kappa = (3 - nu*) / (1 + nu*)`` for the in-plane constants. Polynomials of
degree ``p`` in ``phi`` and ``psi`` give ``4 p + 2`` basis fields, each an exact
solution of the Navier equations. Around a node, a weighted least-squares fit of the
nodal displacements of its ``k`` nearest nodes by these fields, with the known stress
vector imposed exactly at the node (a free or loaded boundary) and weakly at the other
boundary nodes of the patch, gives the stress at the node. A constant body force adds
the particular field ``u_p = -b r^2 / (2 lambda* + 6 mu)``.

Because every basis field is in equilibrium, the fit averages the lattice's
node-to-node fluctuations over a two-dimensional window without the one-sided bias of
a polynomial fit at a surface.
"""

from __future__ import annotations

import numpy as np

__all__ = ["trefftz_stress", "window_size", "DEGREE", "TRACTION_WEIGHT"]

#: polynomial degree of phi and psi
DEGREE = 6
#: weight of a traction row at the other boundary nodes of a patch (relative to a
#: displacement row, in strain units)
TRACTION_WEIGHT = 10.0
#: nodes per patch for a mesh of 2e4 nodes (the window radius scales as h^(1/2)):
#: (200 scatters twice as much along a hole at 2e4 nodes as 400; 400 biases coarse meshes)
WINDOW_AT_2E4 = 300


def window_size(n_points: int) -> int:
    """Nodes in a patch: ``300 sqrt(N / 2e4)``, in [60, 1000] (a window whose radius
    shrinks like ``h^(1/2)``: the bias falls with it, and the node-to-node scatter of
    the lattice displacement averages over more and more nodes)."""
    return int(np.clip(round(WINDOW_AT_2E4 * np.sqrt(n_points / 2.0e4)), 60, 1000))


class _Basis:
    """Displacement and stress of the ``4 p + 2`` Kolosov-Muskhelishvili fields."""

    def __init__(self, E: float, nu: float, p: int):
        self.E = E
        self.mu = E / (2 * (1 + nu))
        self.kappa = (3 - nu) / (1 + nu)
        self.lam = E * nu / (1 - nu**2)  # in-plane lambda*
        self.terms = [("phi", k, c) for k in range(p + 1) for c in (1.0, 1j)]
        self.terms += [("psi", k, c) for k in range(1, p + 1) for c in (1.0, 1j)]

    @property
    def size(self) -> int:
        return len(self.terms)

    def displacement(self, z: np.ndarray) -> np.ndarray:
        """``2 mu u`` (complex ux + i uy) of every field at ``z``, shape z.shape + (nb,)."""
        powers = self._powers(z)
        out = np.empty(z.shape + (self.size,), dtype=complex)
        for col, (kind, k, c) in enumerate(self.terms):
            if kind == "phi":
                d1 = c * k * powers[k - 1] if k >= 1 else 0.0
                out[..., col] = self.kappa * c * powers[k] - z * np.conj(d1)
            else:
                out[..., col] = -np.conj(c * powers[k])
        return out

    def stress(self, z: np.ndarray) -> np.ndarray:
        """``(sxx, syy, sxy)`` of every field at ``z``, shape z.shape + (nb, 3)."""
        powers = self._powers(z)
        out = np.empty(z.shape + (self.size, 3))
        zc = np.conj(z)
        for col, (kind, k, c) in enumerate(self.terms):
            if kind == "phi":
                tr = 4 * np.real(c * k * powers[k - 1]) if k >= 1 else 0.0
                dev = 2 * zc * (c * k * (k - 1) * powers[k - 2]) if k >= 2 else 0.0 * z
            else:
                tr, dev = 0.0, 2 * c * k * powers[k - 1]
            out[..., col, 0] = 0.5 * (tr - dev.real)
            out[..., col, 1] = 0.5 * (tr + dev.real)
            out[..., col, 2] = 0.5 * dev.imag
        return out

    @staticmethod
    def _powers(z: np.ndarray) -> list[np.ndarray]:
        out = [np.ones_like(z)]
        for _ in range(DEGREE):
            out.append(out[-1] * z)
        return out


def trefftz_stress(
    points: np.ndarray,
    u: np.ndarray,
    nodes: np.ndarray,
    E: float,
    nu: float,
    traction: np.ndarray,
    normal: np.ndarray,
    known: np.ndarray,
    body: np.ndarray | None = None,
    k: int | None = None,
    chunk: int = 128,
) -> np.ndarray:
    """Stress (len(nodes), 2, 2) at ``nodes`` from equilibrated fits.

    Parameters
    ----------
    points : ndarray, shape (N, 2)
    u : ndarray, shape (N, 2)
    nodes : ndarray of int
        Where the stress is wanted.
    E, nu : float
        In-plane constants of the (homogeneous) material.
    traction, normal : ndarray, shape (N, 2)
        Known stress vector and outward normal at boundary nodes.
    known : ndarray of bool, shape (N,)
        Nodes whose stress vector is known (free or loaded boundary).
    body : ndarray, shape (len(nodes), 2), optional
        Constant body force (force per volume) around each node.
    k : int, optional
        Nodes per patch (default :func:`window_size`).
    """
    from scipy.spatial import cKDTree

    basis = _Basis(E, nu, DEGREE)
    k = min(k or window_size(len(points)), len(points))
    tree = cKDTree(points)
    out = np.zeros((len(nodes), 2, 2))
    for start in range(0, len(nodes), chunk):
        sel = nodes[start : start + chunk]
        b = None if body is None else body[start : start + chunk]
        dist, idx = tree.query(points[sel], k=k)
        out[start : start + chunk] = _fit(
            basis, points, u, sel, dist, idx, traction, normal, known, b
        )
    return out


def _fit(basis: _Basis, points, u, sel, dist, idx, traction, normal, known, body) -> np.ndarray:
    n, k = idx.shape
    nb = basis.size
    s = 1.2 * dist[:, -1]  # window radius
    z = (
        (points[idx, 0] - points[sel, None, 0]) + 1j * (points[idx, 1] - points[sel, None, 1])
    ) / s[:, None]
    w = (1.0 - (dist / s[:, None]) ** 2) ** 2
    two_mu = 2 * basis.mu
    U = basis.displacement(z)  # (n, k, nb)
    A = np.concatenate([U.real, U.imag], axis=1)  # (n, 2k, nb)
    data = two_mu * np.concatenate([u[idx, 0], u[idx, 1]], axis=1)  # (n, 2k)
    if body is not None:
        data -= two_mu * np.concatenate(_particular(basis, z * s[:, None], body), axis=1)
    W = np.concatenate([w, w], axis=1)
    AW = A * W[..., None]
    M = np.swapaxes(AW, 1, 2) @ A
    rhs = (np.swapaxes(AW, 1, 2) @ data[..., None])[..., 0]
    # weak traction rows at the other known boundary nodes of the patch
    S = basis.stress(z) / s[:, None, None, None]  # (n, k, nb, 3)
    nrm = normal[idx]  # (n, k, 2)
    rows = np.stack(
        [
            S[..., 0] * nrm[..., 0, None] + S[..., 2] * nrm[..., 1, None],
            S[..., 2] * nrm[..., 0, None] + S[..., 1] * nrm[..., 1, None],
        ],
        axis=2,
    )  # (n, k, 2, nb): stress vector of every field
    tv = traction[idx]  # (n, k, 2)
    if body is not None:
        tv = tv - np.einsum("nkij,nkj->nki", _particular_stress(basis, z * s[:, None], body), nrm)
    # a stress row in displacement units (like the data: 2 mu u): stress * s / E * 2 mu
    scale2 = (two_mu * s / basis.E) ** 2
    wt = TRACTION_WEIGHT * w * known[idx] * scale2[:, None]
    wt[:, 0] = 0.0  # the node itself: imposed exactly below
    R = rows.reshape(n, 2 * k, nb)
    RW = R * np.repeat(wt, 2, axis=1)[..., None]
    M += np.swapaxes(RW, 1, 2) @ R
    rhs += (np.swapaxes(RW, 1, 2) @ tv.reshape(n, 2 * k, 1))[..., 0]
    M += 1e-12 * np.trace(M, axis1=1, axis2=2)[:, None, None] * np.eye(nb)
    # exact stress vector at the node where it is known: KKT system with two rows
    K = np.zeros((n, nb + 2, nb + 2))
    K[:, :nb, :nb] = M
    C = rows[:, 0]  # (n, 2, nb) at the node (z = 0)
    own = known[sel]
    K[own, :nb, nb:] = np.swapaxes(C[own], 1, 2)
    K[own, nb:, :nb] = C[own]
    K[~own, nb:, nb:] = np.eye(2)
    r = np.concatenate([rhs, np.where(own[:, None], tv[:, 0], 0.0)], axis=1)
    coef = np.linalg.solve(K, r[..., None])[:, :nb, 0]
    sig = np.einsum("nic,ni->nc", S[:, 0], coef)  # (n, 3); the particular part is 0 there
    return np.stack(
        [np.stack([sig[:, 0], sig[:, 2]], -1), np.stack([sig[:, 2], sig[:, 1]], -1)], -2
    )


def _particular(basis: _Basis, dz: np.ndarray, body: np.ndarray):
    """``u_p = -b r^2 / (2 lambda* + 6 mu)`` at offsets ``dz`` (complex), as (ux, uy)."""
    c = -1.0 / (2 * basis.lam + 6 * basis.mu)
    r2 = np.abs(dz) ** 2
    return c * body[:, 0, None] * r2, c * body[:, 1, None] * r2


def _particular_stress(basis: _Basis, dz: np.ndarray, body: np.ndarray) -> np.ndarray:
    """Stress (n, k, 2, 2) of the particular field: ``grad u_p = 2 c b (x) x``."""
    c = -1.0 / (2 * basis.lam + 6 * basis.mu)
    x = np.stack([dz.real, dz.imag], -1)  # (n, k, 2)
    grad = 2 * c * body[:, None, :, None] * x[..., None, :]  # d u_i / d x_j
    eps = 0.5 * (grad + np.swapaxes(grad, -1, -2))
    tr = eps[..., 0, 0] + eps[..., 1, 1]
    return basis.lam * tr[..., None, None] * np.eye(2) + 2 * basis.mu * eps
