"""Stress recovery of a linear solution that is right at boundaries (the default of
:meth:`Solution.stress <dvstatic.solvers.Solution.stress>`).

The lattice strain of a triangle (its P1 strain) fluctuates from triangle to triangle
on an irregular mesh, and the force-based (virial) stress of a surface particle sees
only half a cell. The recovery therefore works in two parts:

* **patch fit** (every node): a least-squares linear fit, weighted by area and a smooth
  kernel, through the strains of the ``k`` triangles nearest to the node (centroid
  samples, triangles of the node's material only), evaluated at the node; the
  continuum law of that material turns it into stress (plane strain: the in-plane
  effective constants);
* **strain gauge** (nodes on a free or loaded boundary, away from corners and
  supports): the stress vector on the boundary is known, ``sigma n = t`` (zero on a
  free edge, the applied traction or pressure otherwise), and the strain along the
  boundary is measured directly: a quadratic fit of the displacement against the arc
  length over the neighbouring boundary nodes gives ``eps_tt = t . du/ds``; then
  ``sigma_tt = E eps_tt + nu sigma_nn`` (plane strain: ``E*``, ``nu*``). No one-sided
  normal derivative is needed, which is what spoils patch fits at a surface.
"""

from __future__ import annotations

import numpy as np

from ..lattice import VoronoiModel
from ..mesh import Mesh
from ..problem import (
    PointLoad,
    Pressure,
    Traction,
    constraints,
    evaluate,
    select_edges,
    select_nodes,
)
from .trefftz import patches, trefftz_stress, window_size

__all__ = ["recovered_stress", "PATCH_TRIANGLES", "GAUGE_NODES", "CORNER_DEGREES"]

#: triangles in the patch of every node
PATCH_TRIANGLES = 30
#: boundary nodes on each side of a node in its strain gauge
GAUGE_NODES = 3
#: a concave boundary whose radius of curvature is under this many spacings is a
#: hole: its nodes are fitted with the Laurent fields about its centre
HOLE_RADII = 200.0
#: boundary nodes on each side of a node in the smoothing along the boundary
SMOOTH_NODES = 3
#: a boundary node whose edges turn by more than this is a corner (patch fit there)
CORNER_DEGREES = 20.0


def recovered_stress(model: VoronoiModel, u: np.ndarray, supports=(), loads=()) -> np.ndarray:
    """Nodal stress (N, 2, 2) of a linear solution (force per area).

    Parameters
    ----------
    model : DV or RV
    u : ndarray, shape (N, 2)
    supports, loads
        The solution's supports and loads: boundary nodes with a prescribed
        displacement keep the patch fit; tractions and pressures give the stress
        vector of the gauge nodes.
    """
    mesh = model.mesh
    strain = triangle_strains(mesh, u)
    node_mat = _node_material(model)
    eps = _patch_fit(mesh, strain, node_mat, model.material_of_triangle)
    sigma = _law(model, node_mat, eps)
    if not mesh.is_periodic:
        _boundary(model, u, sigma, node_mat, supports, loads)
    return sigma


def triangle_strains(mesh: Mesh, u: np.ndarray) -> np.ndarray:
    """P1 strain ``(exx, eyy, exy)`` of every triangle, shape (M, 3)."""
    x = mesh.triangle_coordinates()
    ut = np.asarray(u)[mesh.triangles]
    d1, d2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    inv = (
        np.stack([np.c_[d2[:, 1], -d2[:, 0]], np.c_[-d1[:, 1], d1[:, 0]]], axis=1)
        / det[:, None, None]
    )
    du = np.stack([ut[:, 1] - ut[:, 0], ut[:, 2] - ut[:, 0]], axis=1)  # (M, 2 edges, 2 comps)
    grad = np.einsum("mej,mei->mij", inv, du)  # grad[m, i, j] = d u_i / d x_j
    return np.c_[grad[:, 0, 0], grad[:, 1, 1], 0.5 * (grad[:, 0, 1] + grad[:, 1, 0])]


def _node_material(model: VoronoiModel) -> np.ndarray:
    """Material index of every node: the one covering most of its triangles' area."""
    mesh = model.mesh
    mat = model.material_of_triangle
    n_mat = 1 + len(model.materials)
    if n_mat == 1:
        return np.zeros(mesh.n_points, dtype=np.int64)
    share = np.zeros((mesh.n_points, n_mat))
    for v in range(3):
        np.add.at(share, (mesh.triangles[:, v], mat), mesh.triangle_areas)
    return np.argmax(share, axis=1)


def _patch_fit(mesh: Mesh, strain: np.ndarray, node_mat, tri_mat) -> np.ndarray:
    """Linear weighted least squares (weights: area times a smooth kernel) through the
    centroid strains of the nearest triangles of the node's material, evaluated at every
    node, shape (N, 3)."""
    from scipy.spatial import cKDTree

    centroids = mesh.triangle_coordinates().mean(axis=1)
    out = np.zeros((mesh.n_points, 3))
    for m in np.unique(node_mat):
        tris = np.flatnonzero(tri_mat == m)
        nodes = np.flatnonzero(node_mat == m)
        k = min(PATCH_TRIANGLES, len(tris))
        dist, idx = cKDTree(centroids[tris]).query(mesh.points[nodes], k=k)
        dist, idx = dist.reshape(len(nodes), k), tris[idx.reshape(len(nodes), k)]
        radius = 1.2 * dist[:, -1:] + 1e-300
        # area weights: small (softer, more strained) triangles of an irregular mesh
        # would otherwise bias the mean (by 1.4 % under uniform stress at 6k nodes)
        w = (1.0 - (dist / radius) ** 2) ** 2 * mesh.triangle_areas[idx]
        d = (centroids[idx] - mesh.points[nodes][:, None, :]) / radius[..., None]
        degree = 1 if k >= 4 else 0  # linear: a third of the quadratic fit's noise
        basis = _monomials(d[..., 0], d[..., 1], degree)  # (n, k, q)
        bw = np.swapaxes(basis * w[..., None], 1, 2)  # (n, q, k)
        a = bw @ basis
        a += 1e-12 * np.trace(a, axis1=1, axis2=2)[:, None, None] * np.eye(a.shape[1])
        b = bw @ strain[idx]
        out[nodes] = np.linalg.solve(a, b)[:, 0, :]  # the constant term: value at the node
    return out


def _monomials(x: np.ndarray, y: np.ndarray, degree: int) -> np.ndarray:
    cols = [np.ones_like(x)]
    if degree >= 1:
        cols += [x, y]
    if degree >= 2:
        cols += [x * x, x * y, y * y]
    return np.stack(cols, axis=-1)


def _law(model: VoronoiModel, node_mat: np.ndarray, eps: np.ndarray) -> np.ndarray:
    """In-plane stress (N, 2, 2) of strains (N, 3) with each node's material."""
    consts = np.array([m.in_plane for m in model.all_materials])  # (E*, nu*) per material
    E, nu = consts[node_mat, 0], consts[node_mat, 1]
    c = E / (1 - nu**2)
    sxx = c * (eps[:, 0] + nu * eps[:, 1])
    syy = c * (eps[:, 1] + nu * eps[:, 0])
    sxy = E / (1 + nu) * eps[:, 2]
    return np.stack([np.stack([sxx, sxy], -1), np.stack([sxy, syy], -1)], -2)


def _boundary(model: VoronoiModel, u, sigma, node_mat, supports, loads) -> None:
    """Overwrite ``sigma`` at the boundary nodes: equilibrated (Trefftz) fits where the
    patch is of one material, the strain gauge elsewhere on free or loaded pieces."""
    mesh = model.mesh
    fixed = np.zeros(mesh.n_points, dtype=bool)
    if supports:
        dofs, _ = constraints(mesh, supports)
        fixed[dofs // 2] = True
    frames = _Frames(model, u, node_mat, fixed, _Tractions(mesh, loads))
    nodes = mesh.boundary_nodes
    body = _body_forces(model, loads, nodes)
    idx, dist = patches(mesh.points, _adjacency(mesh), nodes, window_size(mesh.n_points))
    centres = _hole_centres(mesh, frames, nodes)
    # a patch of one material only (the fields are those of a homogeneous body)
    homogeneous = np.all((node_mat[idx] == node_mat[nodes][:, None]) | ~np.isfinite(dist), axis=1)
    consts = [m.in_plane for m in model.all_materials]
    for m, (E, nu) in enumerate(consts):
        rows = np.flatnonzero((node_mat[nodes] == m) & homogeneous)
        if len(rows):
            sel = nodes[rows]
            sigma[sel] = trefftz_stress(
                mesh.points,
                u,
                sel,
                E,
                nu,
                frames.traction,
                frames.normal,
                frames.known,
                (idx[rows], dist[rows]),
                body=None if body is None else body[rows],
                centres=centres[rows],
            )
            frames.gauge_ok[sel] = False
    sigma[frames.gauge_ok] = frames.gauge[frames.gauge_ok]
    _smooth_along(mesh, sigma, frames)


def _smooth_along(mesh: Mesh, sigma: np.ndarray, frames) -> None:
    """Quadratic least squares of the stress along the boundary (``sigma_tt``) over
    ``SMOOTH_NODES`` nodes on each side, on every free or loaded piece: it removes the
    node-to-node scatter that the lattice's surface displacements leave, and keeps
    peaks (a quadratic is reproduced). ``sigma_nn`` and ``sigma_nt`` are the known
    stress vector and stay."""
    for chain, closed in frames.chains:
        nodes = chain[frames.known[chain]]
        if len(nodes) < 2 * SMOOTH_NODES + 1:
            continue
        t = frames.tangent[nodes]
        s_tt = np.einsum("ni,nij,nj->n", t, sigma[nodes], t)
        p = mesh.points[nodes]
        seg = np.hypot(*np.diff(np.vstack([p, p[:1]]) if closed else p, axis=0).T)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        smooth = _savitzky_golay(s, s_tt, closed)
        sigma[nodes] += (smooth - s_tt)[:, None, None] * np.einsum("ni,nj->nij", t, t)


def _savitzky_golay(s: np.ndarray, v: np.ndarray, closed: bool) -> np.ndarray:
    """Values ``v`` at arc lengths ``s`` smoothed by local quadratic fits over
    ``SMOOTH_NODES`` neighbours on each side (one-sided at the ends of an open piece)."""
    n = len(v)
    m = SMOOTH_NODES
    offs = np.arange(-m, m + 1)
    out = np.empty(n)
    for i in range(n):
        if closed:
            j = (i + offs) % n
            si = _wrapped(s, i, offs, n, s[-1])
        else:
            lo = min(max(i - m, 0), n - 2 * m - 1)
            j = np.arange(lo, lo + 2 * m + 1)
            si = s[j] - s[i]
        coef = np.polyfit(si, v[j], 2)
        out[i] = coef[-1]
    return out


def _hole_centres(mesh: Mesh, frames, nodes: np.ndarray) -> np.ndarray:
    """Centre (x, y) and radius of curvature of the boundary at ``nodes`` where it bends
    around a hole (the centre outside the body, at most HOLE_RADII spacings away), NaN
    elsewhere; shape (len(nodes), 3)."""
    k = frames.curvature[nodes]
    kk = np.einsum("ij,ij->i", k, k)
    out = np.full((len(nodes), 3), np.nan)
    radius = 1.0 / np.sqrt(np.maximum(kk, 1e-300))
    hole = (
        frames.known[nodes]
        & (np.einsum("ij,ij->i", k, frames.normal[nodes]) > 0)
        & (radius < HOLE_RADII * mesh.h)
    )
    out[hole, :2] = mesh.points[nodes[hole]] + k[hole] / kk[hole, None]
    out[hole, 2] = radius[hole]
    return out


def _adjacency(mesh: Mesh):
    """Node adjacency of the bonds, CSR (N, N) bool."""
    import scipy.sparse as sp

    b = mesh.topology.bonds
    n = mesh.n_points
    a = sp.coo_matrix((np.ones(len(b), dtype=bool), (b[:, 0], b[:, 1])), shape=(n, n))
    return (a + a.T).tocsr().astype(bool)


def _body_forces(model: VoronoiModel, loads, nodes: np.ndarray) -> np.ndarray | None:
    """The body force (force per volume) at ``nodes`` (len, 2), None without any."""
    from ..problem import BodyForce

    forces = [ld for ld in loads or () if isinstance(ld, BodyForce)]
    if not forces:
        return None
    mesh = model.mesh
    out = np.zeros((len(nodes), 2))
    x = mesh.points[nodes]
    for ld in forces:
        inside = np.ones(len(nodes), dtype=bool)
        if ld.region is not None:
            in_region = np.zeros(mesh.n_points, dtype=bool)
            in_region[mesh.triangles[mesh.regions[ld.region]].ravel()] = True
            inside = in_region[nodes]
        v = evaluate(ld.value, x, (2,), "BodyForce") if callable(ld.value) else np.asarray(ld.value)
        out += np.where(inside[:, None], v, 0.0)
    return out


class _Frames:
    """Per boundary node: outward normal, whether its stress vector is known (a free
    or loaded piece, not a point load, not a supported node inside a piece) and that
    vector, and the strain-gauge stress."""

    def __init__(self, model: VoronoiModel, u, node_mat, fixed, traction: _Tractions):
        mesh = model.mesh
        n = mesh.n_points
        self.normal = np.zeros((n, 2))
        self.traction = np.zeros((n, 2))
        self.known = np.zeros(n, dtype=bool)
        self.gauge = np.zeros((n, 2, 2))
        self.gauge_ok = np.zeros(n, dtype=bool)
        self.tangent = np.zeros((n, 2))
        self.curvature = np.zeros((n, 2))  # curvature vector (towards the centre)
        self.chains = _boundary_chains(mesh, fixed)
        consts = np.array([m.in_plane for m in model.all_materials])
        for chain, closed in self.chains:
            for i, t, nrm, eps_tt, kvec in _gauge_strains(mesh.points[chain], u[chain], closed):
                node = chain[i]
                inside = closed or 0 < i < len(chain) - 1
                if self.known[node] or (fixed[node] and inside) or node in traction.point_nodes:
                    continue
                tv = traction.at(node, mesh.points[node], nrm)
                s_nn, s_tn = float(tv @ nrm), float(tv @ t)
                E, nu = consts[node_mat[node]]
                s_tt = E * eps_tt + nu * s_nn
                self.gauge[node] = (
                    s_tt * np.outer(t, t)
                    + s_nn * np.outer(nrm, nrm)
                    + s_tn * (np.outer(t, nrm) + np.outer(nrm, t))
                )
                self.normal[node], self.traction[node], self.tangent[node] = nrm, tv, t
                self.curvature[node] = kvec
                self.known[node] = self.gauge_ok[node] = True


def _boundary_chains(mesh: Mesh, fixed: np.ndarray) -> list[tuple[np.ndarray, bool]]:
    """The boundary loops as node chains (body on the left), cut at corners and where
    supported edges (both ends with a prescribed displacement) begin or end; only the
    pieces without supported edges: (nodes, closed)."""
    be = mesh.boundary_edges
    nxt = np.full(mesh.n_points, -1)
    nxt[be[:, 0]] = be[:, 1]
    seen = np.zeros(mesh.n_points, dtype=bool)
    out = []
    for start in be[:, 0]:
        if seen[start]:
            continue
        loop = [start]
        seen[start] = True
        j = nxt[start]
        while j != start and j >= 0 and not seen[j]:
            loop.append(j)
            seen[j] = True
            j = nxt[j]
        out.extend(_pieces(mesh.points, np.array(loop), fixed))
    return out


def _pieces(
    points: np.ndarray, loop: np.ndarray, fixed: np.ndarray
) -> list[tuple[np.ndarray, bool]]:
    """Smooth free pieces of a loop: cut at corners and at the ends of supported runs."""
    p = points[loop]
    d_in = p - np.roll(p, 1, axis=0)
    d_out = np.roll(p, -1, axis=0) - p
    cos = np.einsum("ij,ij->i", d_in, d_out) / (np.hypot(*d_in.T) * np.hypot(*d_out.T))
    supported = fixed[loop] & fixed[np.roll(loop, -1)]  # edge from node k to k + 1
    cut = (cos < np.cos(np.radians(CORNER_DEGREES))) | (supported != np.roll(supported, 1))
    if not cut.any():
        return [] if supported.all() else [(loop, True)]
    first = int(np.argmax(cut))
    loop, cut, supported = (np.roll(a, -first) for a in (loop, cut, supported))
    starts = np.flatnonzero(cut)
    pieces = []
    for a, b in zip(starts, np.r_[starts[1:], len(loop)], strict=True):
        if supported[a]:
            continue  # a run of supported edges: its stress vector is a reaction
        pieces.append((loop[np.r_[np.arange(a, b), b % len(loop)]], False))
    return pieces


def _gauge_strains(p: np.ndarray, u: np.ndarray, closed: bool):
    """For every node of a smooth boundary piece: its position in the piece, unit
    tangent, outward normal and the strain along the boundary from a quadratic fit of u
    against arc length over up to GAUGE_NODES nodes on each side (one-sided at the ends
    of an open piece)."""
    n = len(p)
    if n < 3:
        return
    seg = np.hypot(*np.diff(np.vstack([p, p[:1]]) if closed else p, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    offs = np.arange(-GAUGE_NODES, GAUGE_NODES + 1)
    for i in range(n):
        if closed:
            j = (i + offs) % n
            si = _wrapped(s, i, offs, n, s[-1])
        else:
            lo = min(max(i - GAUGE_NODES, 0), max(n - 2 * GAUGE_NODES - 1, 0))
            j = np.arange(lo, min(lo + 2 * GAUGE_NODES + 1, n))
            si = s[j] - s[i]
        w = np.sqrt(1.0 / (1.0 + (si / (np.abs(si).max() + 1e-300)) ** 2))
        vand = np.c_[np.ones_like(si), si, si**2] * w[:, None]
        coef, *_ = np.linalg.lstsq(vand, u[j] * w[:, None], rcond=None)
        dp, *_ = np.linalg.lstsq(vand, p[j] * w[:, None], rcond=None)
        t = dp[1] / np.hypot(*dp[1])
        normal = np.array([t[1], -t[0]])  # the body is on the left: outward is to the right
        yield i, t, normal, float(t @ coef[1]), 2 * dp[2]


def _wrapped(s: np.ndarray, i: int, offs: np.ndarray, n: int, total: float) -> np.ndarray:
    """Arc length of nodes ``i + offs`` of a closed loop relative to node i."""
    k = i + offs
    return s[k % n] + np.floor_divide(k, n) * total - s[i]


class _Tractions:
    """The applied stress vector at boundary nodes: tractions and pressures of the
    loads on the node's edges (zero on free edges)."""

    def __init__(self, mesh: Mesh, loads):
        self.items = []
        self.point_nodes: set[int] = set()
        for load in loads or ():
            if isinstance(load, (Traction, Pressure)):
                edges = select_edges(mesh, load.where, type(load).__name__)
                nodes = np.zeros(mesh.n_points, dtype=bool)
                nodes[edges.ravel()] = True
                self.items.append((load, nodes))
            elif isinstance(load, PointLoad):
                nodes = select_nodes(mesh, load.nodes, "PointLoad")
                self.point_nodes.update(int(i) for i in np.atleast_1d(nodes))

    def at(self, node: int, x: np.ndarray, normal: np.ndarray) -> np.ndarray:
        out = np.zeros(2)
        for load, nodes in self.items:
            if not nodes[node]:
                continue
            if isinstance(load, Pressure):
                p = evaluate(load.p, x[None], (), "Pressure")[0] if callable(load.p) else load.p
                out -= float(p) * normal
            else:
                v = load.value
                out += evaluate(v, x[None], (2,), "Traction")[0] if callable(v) else np.asarray(v)
        return out
