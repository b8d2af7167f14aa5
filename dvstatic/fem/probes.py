"""Point location and evaluation of FE fields at arbitrary points (the lattice nodes,
which are FE vertices, read their nodal dofs)."""

from __future__ import annotations

import logging

import numpy as np

from ..errors import InputError
from .mesh import FEMesh

__all__ = ["FINDER_CHUNK", "FACET_CHUNK", "probe_matrix"]

log = logging.getLogger(__name__)

#: boundary facets per scikit-fem FacetBasis (the load vector), and points per inversion
#: of curved elements' maps
FACET_CHUNK = 256

#: points per call of scikit-fem's element finder, which maps every point into every
#: candidate element of the whole call (memory ~ points x candidates: 15.6 GiB for 16,835
#: points in one call, 40 MB in chunks)
FINDER_CHUNK = 256


def _cells(fe: FEMesh, x: np.ndarray) -> np.ndarray:
    """The element of every point (x: (2, n)), in chunks of :data:`FINDER_CHUNK`."""
    finder = fe.linear.element_finder()
    if x.shape[1] <= FINDER_CHUNK:
        return _cells_chunk(fe, finder, x)
    return np.concatenate(
        [
            _cells_chunk(fe, finder, x[:, i : i + FINDER_CHUNK])
            for i in range(0, x.shape[1], FINDER_CHUNK)
        ]
    )


def _cells_chunk(fe: FEMesh, finder, x: np.ndarray) -> np.ndarray:
    """The element of every point (2, n); points on the boundary (where round-off can
    put them just outside) are moved a hair towards the nearest element's centroid."""
    try:
        return finder(*x)
    except ValueError:
        pass
    from scipy.spatial import cKDTree

    m = fe.linear
    centroids = m.p[:, m.t].mean(axis=1).T
    _, near = cKDTree(centroids).query(x.T)
    nudged = x + 1e-9 * (centroids[near].T - x)
    try:
        return finder(*nudged)
    except ValueError:
        raise InputError("a point lies outside the mesh", "points") from None


def _reference_points(basis, x: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Reference coordinates of points ``x`` (2, n) in their ``cells``, in chunks (see
    :data:`FACET_CHUNK`), shape (2, n, 1). Where scikit-fem's Newton inversion of a
    curved (quadratic) element fails (a point between the straight edge and the true
    curve, outside the curved element), the chunk's points use the affine map of their
    cell's corners instead (exact on straight elements; on a curved edge it errs by
    the curve's sagitta over the element)."""
    chunks = range(0, x.shape[1], FACET_CHUNK) if x.shape[1] else [0]
    out = []
    for i in chunks:
        sl = slice(i, i + FACET_CHUNK)
        try:
            out.append(basis.mapping.invF(x[:, sl, None], tind=cells[sl]))
        except Exception:  # noqa: BLE001 - scikit-fem's Newton raises a bare Exception
            log.info(
                "FE point location: affine reference coordinates for %d points", x[:, sl].shape[1]
            )
            out.append(_affine_reference(basis, x[:, sl], cells[sl]))
    return np.concatenate(out, axis=1)


def _affine_reference(basis, x: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Reference coordinates (2, n, 1) of points in the triangles of their cells' first
    three (corner) nodes."""
    mesh = basis.mesh
    corners = mesh.p[:, mesh.t[:3, cells]]  # (2, 3, n)
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    d1, d2 = b - a, c - a
    det = d1[0] * d2[1] - d1[1] * d2[0]
    r = x - a
    xi = (r[0] * d2[1] - r[1] * d2[0]) / det
    eta = (d1[0] * r[1] - d1[1] * r[0]) / det
    return np.stack([xi, eta])[..., None]


def probe_matrix(basis, fe: FEMesh, p: np.ndarray):
    """The matrix that evaluates a field of ``basis`` at points ``p`` (n, 2) (scikit-fem's
    ``probes``, with the cells found on the straight-sided mesh so that quadratic
    geometry works too). Points that are mesh vertices (the lattice nodes, where
    outputs are mostly asked for) read their nodal dofs: no point location."""
    from scipy.sparse import coo_matrix
    from scipy.spatial import cKDTree

    comp = int(np.prod(basis._base_tensor_order))
    n = len(p)
    dist, vertex = cKDTree(fe.points).query(p)
    at_vertex = dist == 0.0
    rows_v = np.flatnonzero(at_vertex)
    rows, cols, vals = [], [], []
    for c in range(comp):
        rows.append(c * n + rows_v)
        cols.append(basis.nodal_dofs[c, vertex[rows_v]])
        vals.append(np.ones(rows_v.size))
    rest = np.flatnonzero(~at_vertex)
    if rest.size:
        x = np.ascontiguousarray(p[rest].T)
        cells = _cells(fe, x)
        pts = _reference_points(basis, x, cells)
        phis = np.array(
            [basis.elem.gbasis(basis.mapping, pts, k, tind=cells)[0] for k in range(basis.Nbfun)]
        ).reshape(basis.Nbfun, comp, rest.size)
        dofs = basis.dofs.element_dofs[:, cells].reshape(-1)  # a vector function has one component
        for c in range(comp):
            rows.append(np.tile(c * n + rest, basis.Nbfun))
            cols.append(dofs)
            vals.append(phis[:, c].reshape(-1))
    ij = (np.concatenate(rows), np.concatenate(cols))
    return coo_matrix((np.concatenate(vals), ij), shape=(comp * n, basis.N)).tocsr()
