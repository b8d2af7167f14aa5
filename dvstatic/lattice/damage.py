"""The linear lattice split into triangles, with damage: what breaking a bond means.

The linear stiffness is a sum over triangles (:mod:`dvstatic.lattice.stabilise`)::

    K = sum_T B_T^T Q_T B_T,     Q_T = diag(w_T) + g_T M_T,

``B_T`` (3, 6) the elongation gradients of the triangle's three bonds, ``w_T`` their
spring shares (``tri_weight * spring``), ``g_T`` the triangle's coupling stiffness and
``M_T`` its symmetric coupling matrix (half-side gradients ``dr = M_T B_T``; an exact
boundary cell, :mod:`dvstatic.lattice.cells`, holds ``g_T M_T + dQ_T`` there, with
``g_T`` the mean of its ``w_T``, so it is damaged as a coupling is). The tension
of bond e is ``T_e = sum_{T at e} (Q_T B_T u_T)_e``; ``K u = sum_e T_e grad(delta_e)``
exactly, so these tensions are in equilibrium with the nodal forces.

Damage keeps that form. A bond with stiffness factor ``d_e`` (1 intact, 0 broken) keeps
``d_e`` of its spring in both its triangles, and a triangle one of whose bonds is damaged
(``d_e < 1``) loses its Voronoi coupling (``g_T = 0``): the Voronoi side of a cracked
bond is no longer a cell face, and a coupling without the spring it modulates would make
``Q_T`` indefinite. Every damaged triangle is then a set of plain springs, so each
``Q_T`` stays positive semi-definite (intact triangles are positive definite by the
stabilisation), ``K`` stays symmetric positive semi-definite, a broken bond carries no
tension, and damage never raises a stiffness. A broken bond keeps a tiny residual
fraction of its spring (``RESIDUAL``) so that a piece hanging on a broken bond is not an
exact mechanism; pieces held by nothing else are detected from the bond graph.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from . import assembly
from . import geometry as _geometry
from .kinematics import edge_frames, elongation_gradients
from .operator import RESIDUAL, coupling_factor, term_mask
from .stabilise import coupling_matrices

if TYPE_CHECKING:
    import scipy.sparse as sp

    from .models import VoronoiModel

__all__ = ["RESIDUAL", "TriangleSplit", "split", "csr_rows"]


@dataclass(eq=False)
class TriangleSplit:
    """The per-triangle pieces of a model's linear stiffness.

    Attributes
    ----------
    tri_bonds : (M, 3) int, the bond of every local edge
    b : (M, 3, 6) elongation gradients (dimensionless)
    w : (M, 3) spring share of every local edge (force / length)
    g : (M,) coupling stiffness (force / length)
    m : (M, 3, 3) symmetric coupling matrices (dimensionless)
    dofs : (M, 6) int, the interleaved dofs of every triangle's vertices
    ends : (n_bonds, 2) int, the end nodes of every bond
    """

    tri_bonds: np.ndarray
    b: np.ndarray
    w: np.ndarray
    g: np.ndarray
    m: np.ndarray
    dofs: np.ndarray
    ends: np.ndarray
    #: (M,) bool: triangles whose coupling holds an exact cell's or the regional
    #: isotropy's term (dropped whole at their first damaged bond); None: none
    terms: np.ndarray | None = None

    @cached_property
    def n_bonds(self) -> int:
        return int(self.tri_bonds.max()) + 1

    def factors(self, d: np.ndarray, closed=None, tris=None) -> tuple[np.ndarray, np.ndarray]:
        """Spring shares ``w`` (M, 3) and couplings ``g`` (M,) for bond stiffness factors
        ``d`` (n_bonds,) in [0, 1] (broken bonds keep ``RESIDUAL``); ``closed`` (bool,
        n_bonds): cracks in contact, with their whole spring (the coupling stays off);
        ``tris`` (int array): only these triangles' rows."""
        sl = slice(None) if tris is None else tris
        tb = self.tri_bonds[sl]
        ds = np.maximum(d[tb], RESIDUAL)
        if closed is not None:
            ds = np.where(closed[tb], 1.0, ds)
        return self.w[sl] * ds, self.g[sl] * coupling_factor(d[tb], self.terms, sl)

    def q(self, w: np.ndarray, g: np.ndarray, sl=slice(None)) -> np.ndarray:
        """The 3x3 bond matrices ``Q_T = diag(w_T) + g_T M_T`` of triangles ``sl``."""
        q = g[sl, None, None] * self.m[sl]
        idx = np.arange(3)
        q[:, idx, idx] += w[sl]
        return q

    def forces(self, u: np.ndarray, w: np.ndarray, g: np.ndarray) -> np.ndarray:
        """Every triangle's share of its bonds' tensions, (M, 3), for displacement ``u``
        (2N,)."""
        # q e = w e + g (m e): the elongations and the couplings' products as two sparse
        # products (1.9e5 triangles: 4 ms, against 10 ms with an einsum on the 3x3 m)
        elong = self.elongations @ u
        coupled = (self.coupling @ elong).reshape(-1, 3)
        return w * elong.reshape(-1, 3) + g[:, None] * coupled

    @cached_property
    def coupling(self):
        """(3M, 3M) CSR: the block diagonal of the coupling matrices ``M_T``."""
        import scipy.sparse as sp

        m = len(self.m)
        rows = np.repeat(np.arange(3 * m), 3)
        cols = np.broadcast_to(3 * np.arange(m)[:, None, None] + np.arange(3), (m, 3, 3))
        return sp.csr_matrix((self.m.ravel(), (rows, cols.ravel())), shape=(3 * m, 3 * m))

    @cached_property
    def elongations(self):
        """(3M, 2N) CSR: every triangle's three local bond elongations of a displacement."""
        import scipy.sparse as sp

        m = len(self.b)
        rows = np.repeat(np.arange(3 * m), 6)
        cols = np.broadcast_to(self.dofs[:, None, :], self.b.shape).ravel()
        out = sp.csr_matrix((self.b.ravel(), (rows, cols)), shape=(3 * m, 2 * self.n_nodes))
        out.eliminate_zeros()  # a bond's gradient is 0 at the triangle's third node
        return out

    @cached_property
    def _at_node(self):
        """(N, M) CSR: 1 where a triangle has the node."""
        import scipy.sparse as sp

        m = len(self.b)
        nodes = self.tri_nodes.reshape(m, 3)
        return sp.csr_matrix(
            (np.ones(3 * m), (nodes.ravel(), np.repeat(np.arange(m), 3))),
            shape=(self.n_nodes, m),
        )

    @cached_property
    def _bond_ends(self):
        """(n_bonds, N) CSR: 1 at a bond's two end nodes."""
        import scipy.sparse as sp

        e = len(self.ends)
        return sp.csr_matrix(
            (np.ones(2 * e), (np.repeat(np.arange(e), 2), self.ends.ravel())),
            shape=(e, self.n_nodes),
        )

    @cached_property
    def surface(self) -> np.ndarray:
        """(k,) int: the surface bonds (one triangle), whose patch is that triangle."""
        count = np.bincount(self.tri_bonds.ravel(), minlength=self.n_bonds)
        return np.flatnonzero(count == 1)

    @cached_property
    def _own_tri_of(self) -> np.ndarray:
        """(n_bonds,) int: the one triangle of every surface bond (-1 for the others)."""
        m = len(self.tri_bonds)
        tri = np.empty(self.n_bonds, dtype=np.int64)
        tri[self.tri_bonds.ravel()] = np.repeat(np.arange(m), 3)
        out = np.full(self.n_bonds, -1, dtype=np.int64)
        out[self.surface] = tri[self.surface]
        return out

    @cached_property
    def _surface_tri(self) -> np.ndarray:
        """(k,) int: the one triangle of every surface bond."""
        return self._own_tri_of[self.surface]

    def criterion_total(self, values: np.ndarray) -> np.ndarray:
        """Every bond's sum of per-triangle ``values`` (M,) or (M, k) over its criterion
        patch: the triangles at its two end nodes (:meth:`patch_total`), and a surface
        bond's own triangle alone (a patch reaching two rings into the body smears a
        stress that falls off the surface: at a bore's crown under in-situ compression
        the first crack came 28-37 % late at a / h = 12.5)."""
        out = self.patch_total(values)
        out[self.surface] = values[self._surface_tri]
        return out

    def patch_total(self, values: np.ndarray) -> np.ndarray:
        """Every bond's sum of per-triangle ``values`` (M,) or (M, k) over its patch, the
        triangles at either end node (a triangle at both ends counted twice), shape
        (n_bonds,) or (n_bonds, k): the nodes' sums of their triangles summed over each
        bond's two ends (a third of the work of one bond-by-triangle product)."""
        return self._bond_ends @ (self._at_node @ values)

    def tension(self, u: np.ndarray, w: np.ndarray, g: np.ndarray, forces=None) -> np.ndarray:
        """Bond tensions (n_bonds,) of displacement ``u`` (2N,) (force units); ``forces``
        (from :meth:`forces`) saves recomputing them."""
        f = self.forces(u, w, g) if forces is None else forces
        return np.bincount(self.tri_bonds.ravel(), f.ravel(), self.n_bonds)

    def internal(self, u: np.ndarray, w: np.ndarray, g: np.ndarray) -> np.ndarray:
        """Internal nodal forces ``K u`` (2N,) of displacement ``u`` (2N,), without
        assembling ``K``."""
        fe = np.einsum("mkj,mk->mj", self.b, self.forces(u, w, g))
        return np.bincount(self.dofs.ravel(), fe.ravel(), 2 * self.n_nodes)

    def patch_stress(self, u, w, g, length, area, weight=None, forces=None):
        """Mean stress (n_bonds, 2, 2) around every bond: the area-weighted mean, over the
        triangles at the bond's two end nodes, of the triangle stresses ``sum_k f_k l_k
        n_k (x) n_k / A_T`` (the virial of the triangle's bond-force shares ``f``; it
        equals the triangle's P1 stress ``C_T eps_T``).

        Parameters
        ----------
        length : (M, 3) local bond lengths; area : (M,) triangle areas times the thickness.
        weight : (M,) optional 0/1 weights of the triangles (e.g. only undamaged ones).
        forces : (M, 3) optional, from :meth:`forces`.

        Returns
        -------
        stress : (n_bonds, 2, 2)
        covered : (n_bonds,) bool, False where no triangle of the patch has weight
        """
        v, covered = self.patch_voigt(u, w, g, length, area, weight, forces)
        return v[:, [0, 2, 2, 1]].reshape(-1, 2, 2), covered

    def patch_voigt(self, u, w, g, length, area, weight=None, forces=None):
        """:meth:`patch_stress` as ``(xx, yy, xy)`` (n_bonds, 3) and ``covered``."""
        f = (self.forces(u, w, g) if forces is None else forces) * length
        if weight is not None:
            f *= weight[:, None]
            area = area * weight
        sig = (self._virial @ f.ravel()).reshape(-1, 3)  # sum_k f_k l_k (nx^2, ny^2, nx ny)
        total = self.criterion_total(area)  # the triangles at either end; a surface
        covered = total > 0  # bond's own
        out = self.criterion_total(sig) / np.where(covered, total, 1.0)[:, None]
        return out, covered  # 0 where not covered

    def local_measures(self, u, w, g, length, area, weight, bonds):
        """:meth:`tension` and :meth:`patch_voigt` of ``bonds`` only, from the triangles
        at their end nodes alone (the same sums in the same order as the whole-lattice
        products, so the same numbers): tensions (k,), patch stresses (k, 3) and
        ``covered`` (k,) of ``bonds`` (k,) int, distinct; ``weight`` (M,) or None as in
        :meth:`patch_stress`."""
        import scipy.sparse as sp

        nodes, ends = np.unique(self.ends[bonds], return_inverse=True)
        at = self._at_node
        tri_of, starts = csr_rows(at.indptr, at.indices, nodes)
        tris, pos = np.unique(tri_of, return_inverse=True)
        rows = (3 * tris[:, None] + np.arange(3)).ravel()
        elong = (self.elongations[rows] @ u).reshape(-1, 3)
        f = w[tris] * elong + g[tris, None] * _rowdot(self.m[tris], elong)
        tension = _gather_sum(self.tri_bonds[tris].ravel(), f.ravel(), bonds)
        fl = f * length[tris]
        a = area[tris]
        if weight is not None:
            fl *= weight[tris, None]
            a = a * weight[tris]
        sig = _rowdot(self._virial_rows[tris], fl)
        node_sum = sp.csr_matrix(
            (np.ones(len(pos)), pos, np.r_[starts, len(pos)]), shape=(len(nodes), len(tris))
        )  # the rows ``nodes`` of ``_at_node`` on ``tris``
        node_sig, node_area = node_sum @ sig, node_sum @ a
        ends = ends.reshape(-1, 2)
        total = node_area[ends[:, 0]] + node_area[ends[:, 1]]
        covered = total > 0
        sig_sum = node_sig[ends[:, 0]] + node_sig[ends[:, 1]]
        own_tri = self._own_tri_of[bonds]
        on = np.flatnonzero(own_tri >= 0)  # a surface bond: its triangle
        if len(on):
            own = np.searchsorted(tris, own_tri[on])
            sig_sum[on], total[on] = sig[own], a[own]
            covered = total > 0
        s = sig_sum / np.where(covered, total, 1.0)[:, None]
        return tension, s, covered

    def triangle_change(self, du: np.ndarray) -> np.ndarray:
        """Every triangle's largest elongation change of its edges (length) for the
        displacement change ``du`` (2N,), shape (M,)."""
        e = np.abs(self._bond_elongations @ du)
        tb = self.tri_bonds
        return np.maximum(np.maximum(e[tb[:, 0]], e[tb[:, 1]]), e[tb[:, 2]])

    def patch_max(self, values: np.ndarray, bonds: np.ndarray) -> np.ndarray:
        """The largest of per-triangle ``values`` (M,) over each bond's patch (the
        triangles at its two end nodes), for ``bonds`` (k,) int; shape (k,)."""
        nodes, ends = np.unique(self.ends[bonds], return_inverse=True)
        at = self._at_node
        tris, starts = csr_rows(at.indptr, at.indices, nodes)
        node = np.maximum.reduceat(values[tris], starts) if len(tris) else np.zeros(0)
        ends = ends.reshape(-1, 2)
        return np.maximum(node[ends[:, 0]], node[ends[:, 1]])

    @cached_property
    def _bond_elongations(self):
        """(n_bonds, 2N) CSR: every bond's elongation (the row of its first local edge:
        a bond's elongation is the same seen from either triangle)."""
        _, first = np.unique(self.tri_bonds.ravel(), return_index=True)
        return self.elongations[first]

    def q_norms(self, w: np.ndarray, g: np.ndarray, length=None) -> np.ndarray:
        """Every triangle's largest row sum of ``|Q_T|`` (M,): the largest force share
        per unit elongation of any of its edges; with ``length`` (M, 3), the same of the
        virial rows ``V_T diag(l_T) Q_T`` (a patch stress per unit elongation, times
        area)."""
        q = self.q(w, g)
        if length is not None:
            q = np.einsum("tck,tk,tkl->tcl", self._virial_rows, length, q)
        return np.abs(q).sum(axis=2).max(axis=1)

    @cached_property
    def _virial_rows(self) -> np.ndarray:
        """(M, 3, 3): ``(nx^2, ny^2, nx ny)`` (rows) of every local edge (columns)."""
        n = _local_directions(self.b)
        return np.stack([n[..., 0] ** 2, n[..., 1] ** 2, n[..., 0] * n[..., 1]], axis=1)

    @cached_property
    def _virial(self):
        """(3M, 3M) CSR, block diagonal: a triangle's edge forces times lengths to
        ``sum_k f_k l_k (nx^2, ny^2, nx ny)_k`` (one sparse product, a third of the time
        of the broadcast products)."""
        import scipy.sparse as sp

        m = len(self.b)
        vals = self._virial_rows
        rows = np.broadcast_to(3 * np.arange(m)[:, None, None] + np.arange(3)[:, None], (m, 3, 3))
        cols = np.broadcast_to(3 * np.arange(m)[:, None, None] + np.arange(3), (m, 3, 3))
        return sp.csr_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=(3 * m, 3 * m))

    @cached_property
    def tri_nodes(self) -> np.ndarray:
        return (self.dofs[:, 0::2] // 2).ravel()

    @cached_property
    def n_nodes(self) -> int:
        return int(self.dofs.max()) // 2 + 1

    def stiffness(self, mesh, w: np.ndarray, g: np.ndarray) -> sp.bsr_matrix:
        """The (2N, 2N) BSR stiffness for spring shares ``w`` and couplings ``g``."""
        pat = assembly.pattern(mesh)
        data = np.zeros((pat.nnzb, 4))
        ke = np.einsum("mki,mkl,mlj->mij", self.b, self.q(w, g), self.b)
        assembly.accumulate(pat, ke, data, slice(0, len(ke)))
        return assembly.to_bsr(pat, data)


def _rowdot(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``m @ v`` row by row, (t, 3, 3) times (t, 3), summed in the order of a CSR product
    (so that a few rows give the numbers of the whole-lattice sparse products)."""
    return m[:, :, 0] * v[:, 0, None] + m[:, :, 1] * v[:, 1, None] + m[:, :, 2] * v[:, 2, None]


def _gather_sum(keys: np.ndarray, values: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """Sums of ``values`` by ``keys`` for the keys ``wanted`` (k,) (in key order, as
    ``np.bincount`` sums)."""
    order = np.argsort(wanted)
    sw = wanted[order]
    k = np.minimum(np.searchsorted(sw, keys), len(sw) - 1)
    own = sw[k] == keys
    out = np.empty(len(wanted))
    out[order] = np.bincount(k[own], values[own], len(sw))
    return out


def csr_rows(indptr: np.ndarray, indices: np.ndarray, rows: np.ndarray):
    """The column indices of the rows ``rows`` of a CSR pattern one after another, and
    where each row starts in them."""
    lo, hi = indptr[rows], indptr[rows + 1]
    counts = hi - lo
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    idx = np.repeat(lo - starts, counts) + np.arange(counts.sum())
    return indices[idx], starts


def _local_directions(b: np.ndarray) -> np.ndarray:
    """Unit directions (M, 3, 2) of the local edges from their elongation gradients."""
    from .kinematics import A_OF

    out = np.empty(b.shape[:2] + (2,))
    bb = b.reshape(len(b), 3, 3, 2)
    for k in range(3):
        out[:, k] = bb[:, k, A_OF[k]]
    return out


def split(model: VoronoiModel) -> TriangleSplit:
    """The per-triangle split of ``model``'s linear stiffness (its calibrated, stabilised
    springs and couplings, times the thickness)."""
    op = model.operator
    mesh = model.mesh
    geo = _geometry.of(mesh)
    tb = mesh.topology.tri_bonds
    _, _, n = edge_frames(geo.x_tri)
    tri = mesh.triangles
    dofs = np.stack([2 * tri, 2 * tri + 1], axis=-1).reshape(len(tri), 6)
    w = geo.tri_weight * op.spring[tb]
    g = np.array(op.coupling, dtype=float)
    m = coupling_matrices(mesh, model.barycentric_images)
    if op.cells is not None:  # exact cells: g M + dQ, as one coupling of scale mean(w)
        c = op.cells
        scale = w[c].mean(axis=1)
        m[c] = (g[c, None, None] * m[c] + op.cell_dq) / scale[:, None, None]
        g[c] = scale
    return TriangleSplit(
        tri_bonds=tb,
        b=elongation_gradients(n),
        w=w,
        g=g,
        m=m,
        dofs=dofs,
        ends=mesh.topology.bonds,
        terms=term_mask(op.cells, len(tri)),
    )
