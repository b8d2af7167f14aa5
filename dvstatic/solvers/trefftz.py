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

#: polynomial degree of phi and psi (at most; smaller patches get fewer)
DEGREE = 6
#: patch nodes per unit of degree (a degree-p fit has 4 p + 2 unknowns)
NODES_PER_DEGREE = 10
#: largest Laurent degree about a hole's centre (-p ... p: 8 p + 2 unknowns); the
#: fields of a free or pressurised circular hole in uniform stress need 3
LAURENT_DEGREE = 4
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
    """Displacement and stress of the Kolosov-Muskhelishvili fields: powers ``0..p`` of
    ``phi`` and ``1..p`` of ``psi`` (``4 p + 2`` fields), or with ``laurent`` the powers
    ``-p..p`` about a centre outside the body (a hole's), ``8 p + 2`` fields: those
    represent the fields around a traction-free or pressurised hole exactly."""

    def __init__(self, E: float, nu: float, p: int, laurent: bool = False):
        self.E = E
        self.mu = E / (2 * (1 + nu))
        self.kappa = (3 - nu) / (1 + nu)
        self.lam = E * nu / (1 - nu**2)  # in-plane lambda*
        self.degree = p
        lo = -p if laurent else 0
        self.terms = [("phi", k, c) for k in range(lo, p + 1) for c in (1.0, 1j)]
        self.terms += [("psi", k, c) for k in range(lo, p + 1) if k != 0 for c in (1.0, 1j)]

    @property
    def size(self) -> int:
        return len(self.terms)

    def displacement(self, z: np.ndarray) -> np.ndarray:
        """``2 mu u`` (complex ux + i uy) of every field at ``z``, shape z.shape + (nb,)."""
        pw = _Powers(z)
        out = np.empty(z.shape + (self.size,), dtype=complex)
        for col, (kind, k, c) in enumerate(self.terms):
            if kind == "phi":
                d1 = c * k * pw(k - 1) if k != 0 else 0.0
                out[..., col] = self.kappa * c * pw(k) - z * np.conj(d1)
            else:
                out[..., col] = -np.conj(c * pw(k))
        return out

    def stress(self, z: np.ndarray) -> np.ndarray:
        """``(sxx, syy, sxy)`` of every field at ``z``, shape z.shape + (nb, 3)."""
        pw = _Powers(z)
        out = np.empty(z.shape + (self.size, 3))
        zc = np.conj(z)
        for col, (kind, k, c) in enumerate(self.terms):
            if kind == "phi":
                tr = 4 * np.real(c * k * pw(k - 1)) if k != 0 else 0.0
                dev = 2 * zc * (c * k * (k - 1) * pw(k - 2)) if k not in (0, 1) else 0.0 * z
            else:
                tr, dev = 0.0, 2 * c * k * pw(k - 1)
            out[..., col, 0] = 0.5 * (tr - dev.real)
            out[..., col, 1] = 0.5 * (tr + dev.real)
            out[..., col, 2] = 0.5 * dev.imag
        return out


class _Powers:
    """Integer powers of an array, each computed once."""

    def __init__(self, z: np.ndarray):
        self.z = z
        self.cache: dict[int, np.ndarray] = {0: np.ones_like(z)}

    def __call__(self, k: int) -> np.ndarray:
        if k not in self.cache:
            self.cache[k] = self.z**k if k > 0 else 1.0 / self.z ** (-k)
        return self.cache[k]


def trefftz_stress(
    points: np.ndarray,
    u: np.ndarray,
    nodes: np.ndarray,
    E: float,
    nu: float,
    traction: np.ndarray,
    normal: np.ndarray,
    known: np.ndarray,
    neighbours: tuple[np.ndarray, np.ndarray],
    body: np.ndarray | None = None,
    centres: np.ndarray | None = None,
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
    neighbours : (ndarray, ndarray), shapes (len(nodes), k)
        The patch of every node (its own index first) and the distances; a distance
        of ``inf`` pads a short patch (see :func:`patches`).
    body : ndarray, shape (len(nodes), 2), optional
        Constant body force (force per volume) around each node.
    centres : ndarray, shape (len(nodes), 3), optional
        For nodes on a hole: its centre of curvature (x, y) and radius, NaN elsewhere.
        Those nodes use the Laurent fields about the centre.
    """
    idx_all, dist_all = neighbours
    out = np.zeros((len(nodes), 2, 2))
    if centres is None:
        centres = np.full((len(nodes), 3), np.nan)
    hole = np.isfinite(centres[:, 2])
    # the degree follows the patch: about ten nodes (twenty equations) per degree
    count = np.isfinite(dist_all).sum(axis=1)
    degree = np.where(
        hole,
        np.clip(count // (2 * NODES_PER_DEGREE), 2, LAURENT_DEGREE),
        np.clip(count // NODES_PER_DEGREE, 2, DEGREE),
    )
    for laurent in (False, True):
        for p in np.unique(degree[hole == laurent]):
            basis = _Basis(E, nu, int(p), laurent)
            rows = np.flatnonzero((degree == p) & (hole == laurent))
            for start in range(0, len(rows), chunk):
                r = rows[start : start + chunk]
                out[r] = _fit(
                    basis,
                    points,
                    u,
                    nodes[r],
                    dist_all[r],
                    idx_all[r],
                    (traction, normal, known),
                    None if body is None else body[r],
                    centres[r] if laurent else None,
                )
    return out


def patches(points: np.ndarray, adjacency, nodes: np.ndarray, k: int):
    """The ``k`` nearest nodes of each of ``nodes`` among those reachable through the
    mesh within a few rings of bonds: a window never reaches across a hole or a notch
    to the other side.

    Returns
    -------
    idx : ndarray of int, shape (len(nodes), k)
        The node itself first; short patches are padded with it.
    dist : ndarray, shape (len(nodes), k)
        Distances, ``inf`` for the padding (zero weight).
    """
    import scipy.sparse as sp

    rings = int(np.ceil(np.sqrt(k / 2.5))) + 2
    n = len(points)
    reach = sp.csr_matrix(
        (np.ones(len(nodes), dtype=bool), (np.arange(len(nodes)), nodes)), shape=(len(nodes), n)
    )
    step = (adjacency + sp.identity(n, dtype=bool, format="csr")).astype(bool)
    for _ in range(rings):
        reach = (reach @ step).astype(bool)
    reach = reach.tocsr()
    idx = np.repeat(nodes[:, None], k, axis=1)
    dist = np.full((len(nodes), k), np.inf)
    dist[:, 0] = 0.0
    for r in range(len(nodes)):
        cand = reach.indices[reach.indptr[r] : reach.indptr[r + 1]]
        d = np.hypot(*(points[cand] - points[nodes[r]]).T)
        take = np.argsort(d)[:k]
        idx[r, : len(take)], dist[r, : len(take)] = cand[take], d[take]
    return idx, dist


def _fit(basis: _Basis, points, u, sel, dist, idx, bc, body, centres) -> np.ndarray:
    """Weighted least-squares fit of the fields to the patch displacements, the known
    stress vector imposed at the node; the stress at the node (n, 2, 2)."""
    traction, normal, known = bc
    n, k = idx.shape
    nb = basis.size
    finite = np.isfinite(dist)
    radius = 1.2 * np.max(np.where(finite, dist, 0.0), axis=1)  # window radius
    dz = (points[idx, 0] - points[sel, None, 0]) + 1j * (points[idx, 1] - points[sel, None, 1])
    if centres is None:  # polynomials about the node
        s = radius
        z = dz / s[:, None]
    else:  # Laurent series about the hole's centre, scaled by its radius
        s = centres[:, 2]
        c = centres[:, 0] + 1j * centres[:, 1]
        z = (points[idx, 0] + 1j * points[idx, 1] - c[:, None]) / s[:, None]
    w = np.where(finite, (1.0 - (np.where(finite, dist, 0.0) / radius[:, None]) ** 2) ** 2, 0.0)
    two_mu = 2 * basis.mu
    U = basis.displacement(z)  # (n, k, nb)
    A = np.concatenate([U.real, U.imag], axis=1)  # (n, 2k, nb)
    data = two_mu * np.concatenate([u[idx, 0], u[idx, 1]], axis=1)  # (n, 2k)
    if body is not None:
        data -= two_mu * np.concatenate(_particular(basis, dz, body), axis=1)
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
        tv = tv - np.einsum("nkij,nkj->nki", _particular_stress(basis, dz, body), nrm)
    # a stress row in displacement units (like the data: 2 mu u): stress * s / E * 2 mu
    scale2 = (two_mu * radius / basis.E) ** 2
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
