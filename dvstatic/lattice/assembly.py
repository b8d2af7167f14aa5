"""Sparse assembly of per-triangle 6x6 matrices into 2x2-block (BSR) matrices.

Every DV/RV bond term couples only the three vertices of a triangle (the bond's
two particles and the third vertex that moves the circumcentre), so the lattice
stiffness has exactly the node-to-node pattern of P1 finite elements on the same
triangles. The pattern and the position of each triangle's nine 2x2 blocks in it
are computed once per mesh; assembly is then a single scatter-add.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._cache import PerObject
from ..mesh import Mesh

if TYPE_CHECKING:  # annotations only: scipy is imported where it is used
    import scipy.sparse as sp


__all__ = ["BlockPattern", "pattern", "accumulate", "to_bsr"]


@dataclass(frozen=True, eq=False)
class BlockPattern:
    """Node-level CSR pattern with 2x2 blocks.

    Attributes
    ----------
    n_nodes : int
    indptr : (N + 1,) int32 row pointers
    indices : (nnzb,) int32 block column indices (sorted in each row)
    tri_block : (M * 9,) int64 block index of (local row vertex a, local column vertex b)
        of every triangle, in the order ``3 * a + b``
    diag : (N,) int64 index of the diagonal blocks
    """

    n_nodes: int
    indptr: np.ndarray
    indices: np.ndarray
    tri_block: np.ndarray
    diag: np.ndarray

    @property
    def nnzb(self) -> int:
        return len(self.indices)


def pattern(mesh: Mesh) -> BlockPattern:
    """Block pattern of ``mesh`` (cached per mesh)."""
    return _PATTERN(mesh)


def _build(mesh: Mesh) -> BlockPattern:
    import scipy.sparse as sp

    topo = mesh.topology
    n = mesh.n_points
    o, a = topo.bonds[:, 0], topo.bonds[:, 1]
    nb = len(o)
    rows = np.concatenate([o, a, np.arange(n)])
    cols = np.concatenate([a, o, np.arange(n)])
    if mesh.is_periodic:
        # two bonds may join the same pair of particles through different images
        key = rows * n + cols
        uniq, inv = np.unique(key, return_inverse=True)
        indices = (uniq % n).astype(np.int32)
        counts = np.bincount(uniq // n, minlength=n)
        indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
    else:
        # pairs are unique: let scipy's O(nnz) COO->CSR conversion do the sorting and
        # carry each entry's position through the data array
        c = sp.coo_matrix(
            (np.arange(1, len(rows) + 1, dtype=np.float64), (rows, cols)), shape=(n, n)
        ).tocsr()
        c.sort_indices()
        inv = np.empty(len(rows), dtype=np.int64)
        inv[c.data.astype(np.int64) - 1] = np.arange(len(rows))
        indices, indptr = c.indices.astype(np.int32), c.indptr.astype(np.int32)
    pos_oa, pos_ao, diag = inv[:nb], inv[nb : 2 * nb], inv[2 * nb :]
    tri = mesh.triangles
    m = len(tri)
    tb = np.empty((m, 3, 3), dtype=np.int64)
    for va in range(3):
        for vb in range(3):
            if va == vb:
                tb[:, va, vb] = diag[tri[:, va]]
            else:
                bond = topo.tri_bonds[:, 3 - va - vb]
                forward = tri[:, va] == o[bond]
                tb[:, va, vb] = np.where(forward, pos_oa[bond], pos_ao[bond])
    out = BlockPattern(n, indptr, indices, tb.reshape(-1), diag.astype(np.int64))
    for arr in (indptr, indices, out.tri_block, out.diag):
        arr.setflags(write=False)
    return out


def accumulate(pat: BlockPattern, ke: np.ndarray, data: np.ndarray, sl: slice) -> None:
    """Add triangle matrices ``ke`` (m, 6, 6) of triangles ``sl`` into block data (nnzb, 4)."""
    m = ke.shape[0]
    blocks = ke.reshape(m, 3, 2, 3, 2).transpose(0, 1, 3, 2, 4).reshape(m * 9, 4)
    idx = pat.tri_block[sl.start * 9 : sl.start * 9 + m * 9]
    # spatially ordered meshes touch a narrow band of blocks per chunk
    lo, hi = int(idx.min()), int(idx.max()) + 1
    local = idx - lo
    for c in range(4):
        data[lo:hi, c] += np.bincount(local, weights=blocks[:, c], minlength=hi - lo)


def to_bsr(pat: BlockPattern, data: np.ndarray) -> sp.bsr_matrix:
    """The (2N, 2N) BSR matrix of block data (nnzb, 4) on the pattern."""
    import scipy.sparse as sp

    n2 = 2 * pat.n_nodes
    return sp.bsr_matrix((data.reshape(-1, 2, 2), pat.indices, pat.indptr), shape=(n2, n2))


_PATTERN = PerObject("sparsity pattern", _build)
