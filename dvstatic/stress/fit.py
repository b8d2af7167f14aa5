"""The recovery's averaging: a kernel mean in the interior, equilibrated fits at
boundaries and material interfaces, built once per model as sparse operators.

Every node averages over a window of radius ``R = RADIUS * h`` (``h`` its mean bond
length) with the kernel ``(1 - (d / R)^2)^2`` times the nodes' areas:

* **interior** (the window holds no boundary node and one material): the kernel mean of
  the nodal data, one sparse row per node;
* **band** (the window meets a boundary or another material): a weighted least-squares
  fit by the Kolosov-Muskhelishvili fields of the node's material (powers up to
  ``DEGREE`` about the node; about a hole's centre with the negative powers too, where
  the window reaches a boundary that bends around a hole), to the nodal data of the
  node's own material in the window, the stress vector on the boundary edges in the
  window (``TRACTION_WEIGHT``; components set by support reactions count
  ``REACTION_WEIGHT`` of that), and the stretch of those edges (``STRETCH_WEIGHT``):
  ``E eps_tt = sigma_tt - nu sigma_nn``. The fit is evaluated at the node. Windows
  follow the mesh (nodes a few rings of bonds away, never across a hole or a notch).

Both are linear in the data: :class:`Estimator` keeps them as sparse matrices, so every
further state of the same model (fracture snapshots, the responses of
:mod:`~dvstatic.stress.response`) costs a matrix product. A constant body force adds
the particular field ``sigma_p = -diag(b_x (x - x_i), b_y (y - y_i))`` about each node
(``div sigma_p = -b``, zero at the node); its response is kept per node.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mesh import Mesh, spatial_order
from .boundary import Boundary
from .kolosov import Fields

__all__ = [
    "Estimator",
    "build_estimator",
    "RADIUS",
    "DEGREE",
    "TRACTION_WEIGHT",
    "REACTION_WEIGHT",
    "STRETCH_WEIGHT",
]

#: window radius in local spacings (mean bond length at the node)
RADIUS = 4.0
#: largest power of the K-M fields of the band fits (quadratic stress)
DEGREE = 3
#: largest power of the Laurent fields about a hole's centre
LAURENT_DEGREE = 3
#: weight of a stress-vector row (per edge length x window radius) against a datum
#: (per area)
TRACTION_WEIGHT = 10.0
#: the share of that weight of a component set by a support reaction (a lattice's
#: reactions scatter from node to node, and crowd into corners)
REACTION_WEIGHT = 1.0
#: weight of an edge-stretch row (per edge length x window radius): it steadies the
#: tangential stress where the window is one-sided; the stretch of single boundary
#: edges scatters by 20-40 %, so it only guides
STRETCH_WEIGHT = 0.1
#: nodes per chunk of the vectorised fits
CHUNK = 256


@dataclass(frozen=True, eq=False)
class Estimator:
    """The averaging of every node, as linear operators on the data.

    Attributes
    ----------
    interior : scipy.sparse.csr_matrix, shape (N, N)
        Kernel weights (rows sum to 1) of interior nodes, empty rows elsewhere.
    band : scipy.sparse.csr_matrix, shape (3N, 3N + 3E)
        Weights of the band fits on the data vector ``[nodal (3N, node-major: sxx,
        syy, sxy) | edge stress vector (2E) | E x edge stretch (E)]``; rows
        ``3 i + c`` of band nodes only.
    is_band : ndarray of bool, shape (N,)
    body : ndarray, shape (N, 3, 2)
        Response of every node's estimate to its particular field for a unit body
        force along x and along y (subtract ``body @ b``).
    radius : ndarray, shape (N,)
        The window radius of every node (length).
    """

    interior: object
    band: object
    is_band: np.ndarray
    body: np.ndarray
    radius: np.ndarray

    def apply(self, nodal: np.ndarray, edge_t: np.ndarray, stretch: np.ndarray) -> np.ndarray:
        """Estimates (..., N, 3) from nodal data (..., N, 3), edge stress vectors
        (..., E, 2) and ``E x`` edge stretches (..., E)."""
        lead = nodal.shape[:-2]
        n = nodal.shape[-2]
        nodal2 = nodal.reshape(-1, n, 3)
        data = np.concatenate(
            [
                nodal2.reshape(len(nodal2), -1),
                edge_t.reshape(len(nodal2), -1),
                stretch.reshape(len(nodal2), -1),
            ],
            axis=1,
        )
        out = np.empty_like(nodal2)
        for k in range(len(nodal2)):
            est = (self.interior @ nodal2[k]) + (self.band @ data[k]).reshape(n, 3)
            out[k] = est
        return out.reshape(*lead, n, 3)


def local_spacing(mesh: Mesh) -> np.ndarray:
    """Mean length of the bonds at every node, shape (N,)."""
    b = mesh.topology.bonds
    length = mesh.bond_lengths()
    n = mesh.n_points
    total = np.bincount(b[:, 0], length, n) + np.bincount(b[:, 1], length, n)
    count = np.bincount(b[:, 0], None, n) + np.bincount(b[:, 1], None, n)
    return total / np.maximum(count, 1)


def kernel(r: np.ndarray) -> np.ndarray:
    """``(1 - r^2)^2`` for r < 1, else 0."""
    return np.where(r < 1.0, (1.0 - r * r) ** 2, 0.0)


def build_estimator(
    mesh: Mesh,
    node_mat: np.ndarray,
    tri_mat: np.ndarray,
    consts: np.ndarray,
    area: np.ndarray,
    boundary: Boundary | None,
    fixed: np.ndarray,
    edge_mat: np.ndarray,
) -> Estimator:
    """Build the interior and band operators.

    Parameters
    ----------
    mesh : Mesh
    node_mat : ndarray of int, shape (N,)
        Material of every node (the one of most of its triangles' area).
    tri_mat : ndarray of int, shape (M,)
        Material of every triangle.
    consts : ndarray, shape (n_materials, 2)
        In-plane (E, nu) of every material.
    area : ndarray, shape (N,)
        Nodal area (a third of the node's triangles).
    boundary : Boundary or None
        None for periodic meshes (every node interior).
    fixed : ndarray of bool, shape (N, 2)
        Prescribed dofs.
    edge_mat : ndarray of int, shape (E,)
        Material of every boundary edge's triangle.
    """
    import scipy.sparse as sp
    from scipy.spatial import cKDTree

    n = mesh.n_points
    h = local_spacing(mesh)
    radius = RADIUS * h
    on_boundary = np.zeros(n, dtype=bool)
    if boundary is not None:
        on_boundary[boundary.slot_node] = True
    tree = cKDTree(mesh.points)
    order = spatial_order(mesh.points)
    rows, cols, vals = [], [], []
    band_nodes = []
    for start in range(0, n, 4 * CHUNK):
        chunk = order[start : start + 4 * CHUNK]
        i, j, d = _pairs(tree, mesh.points, chunk, radius)
        foreign = on_boundary[j] | (node_mat[j] != node_mat[chunk][i])
        touched = np.bincount(i, foreign, len(chunk)) > 0
        if boundary is None:
            touched[:] = False
        keep = ~touched[i]
        w = kernel(d[keep] / radius[chunk][i[keep]]) * area[j[keep]]
        rows.append(chunk[i[keep]])
        cols.append(j[keep])
        vals.append(w)
        band_nodes.append(chunk[touched])
    rows, cols, vals = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
    total = np.bincount(rows, vals, n)
    interior = sp.csr_matrix((vals / total[rows], (rows, cols)), shape=(n, n))
    band = np.sort(np.concatenate(band_nodes))
    is_band = np.zeros(n, dtype=bool)
    is_band[band] = True
    body = np.zeros((n, 3, 2))
    body[~is_band] = _interior_body(interior, mesh.points)[~is_band]
    n_edges = 0 if boundary is None else len(boundary.edges)
    shape = (3 * n, 3 * n + 3 * n_edges)
    if len(band) == 0:
        return Estimator(interior, sp.csr_matrix(shape), is_band, body, radius)
    fits = _BandFits(mesh, node_mat, tri_mat, consts, area, boundary, fixed, edge_mat, h, radius)
    parts = [fits.chunk(c) for c in fits.chunks(band)]
    r_ = np.concatenate([p[0] for p in parts])
    c_ = np.concatenate([p[1] for p in parts])
    v_ = np.concatenate([p[2] for p in parts])
    for nodes, resp in ((p[3], p[4]) for p in parts):
        body[nodes] = resp
    band_op = sp.coo_matrix((v_, (r_, c_)), shape=shape).tocsr()
    return Estimator(interior, band_op, is_band, body, radius)


def _pairs(tree, points: np.ndarray, nodes: np.ndarray, radius: np.ndarray):
    """All (node, neighbour) pairs within each node's radius: local row index into
    ``nodes``, neighbour index, distance."""
    from scipy.spatial import cKDTree

    r_max = float(radius[nodes].max())
    coo = cKDTree(points[nodes]).sparse_distance_matrix(tree, r_max, output_type="coo_matrix")
    i, j, d = coo.row, coo.col, coo.data
    # sparse_distance_matrix leaves out the zero distance of a node to itself
    i = np.concatenate([i, np.arange(len(nodes))])
    j = np.concatenate([j, nodes])
    d = np.concatenate([d, np.zeros(len(nodes))])
    keep = d < radius[nodes][i]
    return i[keep], j[keep], d[keep]


def _interior_body(interior, points: np.ndarray) -> np.ndarray:
    """Kernel mean of every node's particular field, shape (N, 3, 2)."""
    out = np.zeros((len(points), 3, 2))
    mean = interior @ points
    out[:, 0, 0] = -(mean[:, 0] - points[:, 0])  # sigma_p,xx = -(x - x_i) for b = (1, 0)
    out[:, 1, 1] = -(mean[:, 1] - points[:, 1])
    return out


class _BandFits:
    """The least-squares fits of the band nodes, chunk by chunk."""

    def __init__(self, mesh, node_mat, tri_mat, consts, area, boundary, fixed, edge_mat, h, radius):
        import scipy.sparse as sp
        from scipy.spatial import cKDTree

        self.mesh, self.node_mat, self.consts, self.area = mesh, node_mat, consts, area
        self.mixed = mixed_nodes(mesh, tri_mat)
        self.b, self.fixed, self.edge_mat, self.h, self.radius = (
            boundary,
            fixed,
            edge_mat,
            h,
            radius,
        )
        n = mesh.n_points
        bonds = mesh.topology.bonds
        a = sp.coo_matrix((np.ones(len(bonds), dtype=bool), (bonds[:, 0], bonds[:, 1])), (n, n))
        self.step = (a + a.T + sp.identity(n, dtype=bool, format="csr")).tocsr().astype(bool)
        self.tree = cKDTree(mesh.points)
        self.edge_tree = cKDTree(boundary.midpoint)
        centres = boundary.hole_centres(mesh.points, h)
        hole = np.isfinite(centres[:, 2])
        self.hole_slots = np.flatnonzero(hole)
        self.hole_centres = centres[hole]
        self.hole_tree = cKDTree(mesh.points[boundary.slot_node[hole]]) if hole.any() else None
        known = ~(fixed[boundary.edges[:, 0]] | fixed[boundary.edges[:, 1]])  # (E, 2)
        self.traction_w = TRACTION_WEIGHT * np.where(known, 1.0, REACTION_WEIGHT)

    def chunks(self, band: np.ndarray):
        """Band nodes grouped by (material, hole centre or none), in chunks."""
        centre = np.full((len(band), 3), np.nan)
        if self.hole_tree is not None:
            d, k = self.hole_tree.query(self.mesh.points[band])
            near = d < self.radius[band]
            centre[near] = self.hole_centres[k[near]]
        key_hole = np.where(np.isfinite(centre[:, 2]), 1, 0)
        for m in np.unique(self.node_mat[band]):
            for lau in (0, 1):
                sel = (self.node_mat[band] == m) & (key_hole == lau)
                nodes = band[sel]
                for s in range(0, len(nodes), CHUNK):
                    yield nodes[s : s + CHUNK], int(m), centre[sel][s : s + CHUNK] if lau else None

    def _windows(self, nodes: np.ndarray, m: int):
        """Window nodes (padded with -1) of every node: own material, within the
        radius, reachable through the mesh within a few rings."""
        import scipy.sparse as sp

        mesh = self.mesh
        i, j, d = _pairs(self.tree, mesh.points, nodes, self.radius)
        rings = int(np.ceil(1.6 * np.max(self.radius[nodes] / self.h[nodes]))) + 1
        reach = sp.csr_matrix(
            (np.ones(len(nodes), dtype=bool), (np.arange(len(nodes)), nodes)),
            shape=(len(nodes), mesh.n_points),
        )
        for _ in range(rings):
            reach = (reach @ self.step).astype(bool)
        # own material; nodes on an interface (triangles of two materials) hold a mix
        ok = _lookup(reach, i, j) & (self.node_mat[j] == m) & ~self.mixed[j]
        i, j, d = i[ok], j[ok], d[ok]
        return _padded(i, j, d, len(nodes)), reach

    def _edge_windows(self, nodes: np.ndarray, m: int, reach):
        from scipy.spatial import cKDTree

        r_max = float(self.radius[nodes].max())
        coo = cKDTree(self.mesh.points[nodes]).sparse_distance_matrix(
            self.edge_tree, r_max, output_type="coo_matrix"
        )
        i, e, d = coo.row, coo.col, coo.data
        ends = self.b.edges[e]
        ok = (
            (d < self.radius[nodes][i])
            & (self.edge_mat[e] == m)
            & _lookup(reach, i, ends[:, 0])
            & _lookup(reach, i, ends[:, 1])
        )
        return _padded(i[ok], e[ok], d[ok], len(nodes))

    def chunk(self, spec):
        """Sparse entries (rows, cols, values) and body-force responses of a chunk."""
        nodes, m, centre = spec
        mesh, n = self.mesh, self.mesh.n_points
        E, nu = self.consts[m]
        (jw, dw), reach = self._windows(nodes, m)
        ew, de = self._edge_windows(nodes, m, reach)
        laurent = centre is not None
        fields = Fields(E, nu, LAURENT_DEGREE if laurent else DEGREE, laurent)
        x0 = mesh.points[nodes]
        R = self.radius[nodes]
        if laurent:
            z0 = centre[:, 0] + 1j * centre[:, 1]
            scale = centre[:, 2]
        else:
            z0 = x0[:, 0] + 1j * x0[:, 1]
            scale = R

        def basis(p):  # (c, k, 2) points -> (c, k, nb, 3)
            z = ((p[..., 0] + 1j * p[..., 1]) - z0[:, None]) / scale[:, None]
            return fields.stress(z)

        # data rows: every window node, its three components (sxy counted twice)
        valid = jw >= 0
        jj = np.where(valid, jw, 0)
        Sd = basis(mesh.points[jj])  # (c, k, nb, 3)
        wd = np.where(valid, kernel(dw / R[:, None]) * self.area[jj], 0.0)
        wd3 = wd[..., None] * np.array([1.0, 1.0, 2.0])  # (c, k, 3)
        # stress-vector and stretch rows on the window's boundary edges
        evalid = ew >= 0
        ee = np.where(evalid, ew, 0)
        Se = basis(self.b.midpoint[ee])  # (c, ke, nb, 3)
        nrm, tan = self.b.normal[ee], self.b.tangent[ee]
        tx = Se[..., 0] * nrm[..., 0, None] + Se[..., 2] * nrm[..., 1, None]
        ty = Se[..., 2] * nrm[..., 0, None] + Se[..., 1] * nrm[..., 1, None]
        stt = _normal_component(Se, tan)
        snn = _normal_component(Se, nrm)
        base = np.where(
            evalid, kernel(de / R[:, None]) * self.b.length[ee] * R[:, None], 0.0
        )  # (c, ke)
        wt = base[..., None] * self.traction_w[ee]  # (c, ke, 2)
        ws = STRETCH_WEIGHT * base
        st_row = stt - nu * snn
        # normal equations
        M = np.einsum("ckbq,ckq,ckdq->cbd", Sd, wd3, Sd)
        M += np.einsum("ckb,ck,ckd->cbd", tx, wt[..., 0], tx)
        M += np.einsum("ckb,ck,ckd->cbd", ty, wt[..., 1], ty)
        M += np.einsum("ckb,ck,ckd->cbd", st_row, ws, st_row)
        M += 1e-10 * np.trace(M, axis1=1, axis2=2)[:, None, None] * np.eye(fields.size)
        s0 = basis(x0[:, None, :])[:, 0]  # (c, nb, 3)
        G = np.linalg.solve(M, s0)  # (c, nb, 3): M^-1 s0
        # weights of every datum on every output component
        kd = np.einsum("ckbq,cbo->ckqo", Sd, G) * wd3[..., None]  # (c, k, 3 comps, 3 out)
        kx = np.einsum("ckb,cbo->cko", tx, G) * wt[..., 0, None]
        ky = np.einsum("ckb,cbo->cko", ty, G) * wt[..., 1, None]
        ks = np.einsum("ckb,cbo->cko", st_row, G) * ws[..., None]
        out_rows = 3 * nodes[:, None] + np.arange(3)  # (c, 3)
        n_e = len(self.b.edges)
        r_ = [
            np.broadcast_to(out_rows[:, None, None, :], kd.shape),
            np.broadcast_to(out_rows[:, None, :], kx.shape),
            np.broadcast_to(out_rows[:, None, :], ky.shape),
            np.broadcast_to(out_rows[:, None, :], ks.shape),
        ]
        c_ = [
            np.broadcast_to((3 * jj[..., None] + np.arange(3))[..., None], kd.shape),
            np.broadcast_to((3 * n + 2 * ee)[..., None], kx.shape),
            np.broadcast_to((3 * n + 2 * ee + 1)[..., None], ky.shape),
            np.broadcast_to((3 * n + 2 * n_e + ee)[..., None], ks.shape),
        ]
        v_ = [kd, kx, ky, ks]
        keep = [
            np.broadcast_to(valid[..., None, None], kd.shape),
            np.broadcast_to(evalid[..., None], kx.shape),
            np.broadcast_to(evalid[..., None], ky.shape),
            np.broadcast_to(evalid[..., None], ks.shape),
        ]
        rows = np.concatenate([r[k] for r, k in zip(r_, keep, strict=True)])
        cols = np.concatenate([c[k] for c, k in zip(c_, keep, strict=True)])
        vals = np.concatenate([v[k] for v, k in zip(v_, keep, strict=True)])
        # responses to the particular fields of a unit body force (x, then y)
        dxj = mesh.points[jj] - x0[:, None, :]  # (c, k, 2)
        dxe = self.b.midpoint[ee] - x0[:, None, :]
        resp = np.zeros((len(nodes), 3, 2))
        for comp in range(2):
            sp_d = np.zeros(dxj.shape[:2] + (3,))
            sp_d[..., comp] = -dxj[..., comp]
            sp_e = np.zeros(dxe.shape[:2] + (3,))
            sp_e[..., comp] = -dxe[..., comp]
            t_e = np.stack(
                [
                    sp_e[..., 0] * nrm[..., 0] + sp_e[..., 2] * nrm[..., 1],
                    sp_e[..., 2] * nrm[..., 0] + sp_e[..., 1] * nrm[..., 1],
                ],
                axis=-1,
            )
            st_e = (
                _normal_component(sp_e[..., None, :], tan)[..., 0]
                - nu * _normal_component(sp_e[..., None, :], nrm)[..., 0]
            )
            resp[:, :, comp] = (
                np.einsum("ckqo,ckq->co", kd, sp_d)
                + np.einsum("cko,ck->co", kx, t_e[..., 0])
                + np.einsum("cko,ck->co", ky, t_e[..., 1])
                + np.einsum("cko,ck->co", ks, st_e)
            )
        return rows, cols, vals, nodes, resp


def mixed_nodes(mesh: Mesh, tri_mat: np.ndarray) -> np.ndarray:
    """Nodes whose triangles are of more than one material, shape (N,) bool."""
    lo = np.full(mesh.n_points, np.iinfo(np.int64).max)
    hi = np.full(mesh.n_points, -1)
    for v in range(3):
        np.minimum.at(lo, mesh.triangles[:, v], tri_mat)
        np.maximum.at(hi, mesh.triangles[:, v], tri_mat)
    return hi > lo


def _lookup(matrix, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """``matrix[i, j] != 0`` for index arrays (a bool array, empty for empty input)."""
    if len(i) == 0:
        return np.zeros(0, dtype=bool)
    return np.asarray(matrix[i, j]).ravel().astype(bool)


def _normal_component(S: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``v . sigma . v`` of stresses ``S (..., nb, 3)`` with directions ``v (..., 2)``."""
    vx, vy = v[..., 0, None], v[..., 1, None]
    return S[..., 0] * vx * vx + S[..., 1] * vy * vy + 2 * S[..., 2] * vx * vy


def _padded(i: np.ndarray, j: np.ndarray, d: np.ndarray, n: int):
    """Rows of (row, column, distance) triples as padded arrays (n, k): -1 / inf pads."""
    order = np.lexsort((d, i))
    i, j, d = i[order], j[order], d[order]
    count = np.bincount(i, minlength=n)
    k = max(int(count.max()), 1)
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    pos = np.arange(len(i)) - start[i]
    jw = np.full((n, k), -1, dtype=np.int64)
    dw = np.full((n, k), np.inf)
    jw[i, pos] = j
    dw[i, pos] = d
    return jw, dw
