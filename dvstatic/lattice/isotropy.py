"""Regional isotropy: the anisotropy a mesher's cells give a region, taken out.

Each linear DV/RV triangle is a P1 element with its own tensor ``C_T``
(:func:`dvstatic.lattice.stabilise.triangle_tensors`). Over a statistically isotropic
mesh the anisotropic parts of the ``C_T`` cancel within a few spacings, and the relaxed
calibration makes the isotropic part right. A mesher's graded or front-advancing cells
do not cancel: they are stretched along the grading and aligned with the fronts, so a
whole region of an isotropic material comes out anisotropic (a gmsh ring graded 0.005
-> 0.02 towards its bore, 17,060 nodes: the regions' mean tensors are 2.6 % anisotropic,
hoop-stiff by 2.3-2.8 % against radial in the graded part, and the Lame displacement is
0.91 % off against 0.11 % on a uniform gmsh ring).

The correction (``anisotropy="regional"``) adds to every lattice triangle the tensor
``-D_R``: the anisotropic part ``D_T = C_T - iso(C_T)`` averaged over the triangle's
region (areas to the nodes, :data:`REGION_RINGS` passes of the neighbour average
:func:`~dvstatic.lattice.calibration.descriptors.ring_mean`, a window about 2.3
spacings wide (standard deviation), back to the triangles), ``iso`` the orthogonal
projection on the isotropic tensors. It acts as an exact cell's term does
(:mod:`dvstatic.lattice.cells`): a bond matrix ``dQ_T = A_T E_T^-T (-D_R) E_T^-1`` on
the triangle's three elongations. It keeps what the calibration set (every triangle's
isotropic part) and the triangle-to-triangle fluctuations (the lattice's
micro-structure); only the regional mean's anisotropy goes.

Where the term would soften a triangle below half of its own bond matrix (``Q_T +
dQ_T`` not above ``Q_T / 2``: :data:`KEEP`) it is scaled down, so the lattice stays as
stable as it was; exact cells (already isotropic) and slivers
(:data:`~dvstatic.lattice.cells.CELL_SINE`) take no term.

Default (``"auto"``, :func:`default_anisotropy`) where it was measured to help: meshes
without a generator recipe (imported; gmsh plates, rings and Cook's membranes:
validation/imported.py) and the generators' graded CVT meshes (the tunnel example at
h_near = 0.0125, seeds 0-3: wall hoop rms 1.77 -> 0.66 %, worst node 4.5 -> 1.9 %, with
the surface springs in place of the fabric's). Not on the package's uniform meshes,
isotropic by construction, where a region's anisotropy is noise that the relaxation
does not follow (Lame at 2e4 nodes, two seeds: jittered L2 0.100 -> 0.097 % but bore
worst node 0.41 -> 0.62 %; random points L2 0.61 -> 1.44 %), nor on graded random points
(tunnel wall rms 3.8 -> 6.0 %).
"""

from __future__ import annotations

import numpy as np

from ..mesh import Mesh
from . import geometry as _geometry
from .calibration.descriptors import ring_mean
from .cells import CELL_SINE, unit_elongations

__all__ = [
    "ANISOTROPY",
    "REGION_RINGS",
    "KEEP",
    "default_anisotropy",
    "isotropic_part",
    "regional_anisotropy",
    "regional_corrections",
]

#: choices of ``anisotropy`` of :class:`dvstatic.DV` / :class:`dvstatic.RV`
ANISOTROPY = ("auto", "regional", "keep")
#: passes of the neighbour average that make a triangle's region
REGION_RINGS = 12
#: the term never takes a triangle's bond matrix below this fraction of its own
KEEP = 0.5

_M = np.array([1.0, 1.0, 0.0])
_J = np.outer(_M, _M) / 2.0  # the bulk projector (Mandel)
_K = np.eye(3) - _J  # the deviatoric projector


def default_anisotropy(mesh: Mesh) -> str:
    """``"regional"`` on meshes without a generator recipe (imported) and on the
    generators' graded CVT meshes, ``"keep"`` on the package's other meshes (uniform
    ones are isotropic by construction; on graded random points the regions'
    anisotropy is noise) and on periodic ones."""
    s = mesh.sampling
    if mesh.is_periodic:
        return "keep"
    return "regional" if s is None or (s.graded and s.kind == "cvt") else "keep"


def resolve_anisotropy(anisotropy: str, mesh: Mesh) -> str:
    """``anisotropy`` resolved for ``mesh`` (``"auto"``: :func:`default_anisotropy`)."""
    return default_anisotropy(mesh) if anisotropy == "auto" else anisotropy


def isotropic_part(tensors: np.ndarray) -> np.ndarray:
    """The orthogonal projection of Mandel tensors (..., 3, 3) on the isotropic ones
    ``a J + b K`` (``J`` bulk, ``K = I - J`` deviatoric projector), same shape."""
    a = np.einsum("...ij,ij->...", tensors, _J)  # J:J = 1
    b = np.einsum("...ij,ij->...", tensors, _K) / 2.0  # K:K = 2
    return a[..., None, None] * _J + b[..., None, None] * _K


def regional_anisotropy(
    mesh: Mesh,
    tensors: np.ndarray,
    lattice: np.ndarray,
    material: np.ndarray | None = None,
    rings: int = REGION_RINGS,
) -> np.ndarray:
    """The anisotropic part of every triangle's regional mean tensor, shape (M, 3, 3).

    Parameters
    ----------
    mesh : Mesh
    tensors : ndarray, shape (M, 3, 3)
        Every triangle's tensor (Mandel, units of E).
    lattice : ndarray of int, shape (k,)
        The triangles whose anisotropy counts (:func:`corrected_triangles`): the
        others count as isotropic, the exact cells since they are, the slivers since
        their near-singular tensors (up to 1 / sine^2) would swamp their region.
    material : ndarray of int, shape (M,), optional
        Every triangle's material: a region is averaged within its triangle's
        material (a stiff inclusion's anisotropy is not a soft matrix's).
    rings : int
        Passes of the neighbour average.
    """
    dev = np.zeros_like(tensors)
    dev[lattice] = tensors[lattice] - isotropic_part(tensors[lattice])
    material = np.zeros(len(dev), dtype=np.int64) if material is None else material
    out = np.zeros_like(dev)
    for k in np.unique(material):
        mine = material == k
        node, touched = _node_means(mesh, dev, mine)
        if not mine.all():  # the mean over the material's own nodes only
            node = ring_mean(mesh, node * touched[:, None], rings)
            node /= np.maximum(ring_mean(mesh, touched, rings), 1e-300)[:, None]
        else:
            node = ring_mean(mesh, node, rings)
        out[mine] = node[mesh.triangles[mine]].mean(axis=1).reshape(-1, 3, 3)
    return out


def _node_means(mesh: Mesh, dev: np.ndarray, mine: np.ndarray):
    """The area-weighted mean (N, 9) of ``dev`` over the triangles ``mine`` at every
    node, and which nodes touch them (N,) float."""
    t, n = mesh.triangles[mine], mesh.n_points
    area = mesh.triangle_areas[mine]
    weight = np.bincount(t.ravel(), np.repeat(area, 3), n)
    flat = dev[mine].reshape(-1, 9) * area[:, None]
    node = np.stack([np.bincount(t.ravel(), np.repeat(flat[:, j], 3), n) for j in range(9)], 1)
    touched = (weight > 0).astype(float)
    return node / np.maximum(weight, 1e-300)[:, None], touched


def regional_corrections(
    mesh: Mesh, idx: np.ndarray, anisotropy: np.ndarray, tensors: np.ndarray
) -> np.ndarray:
    """Bond matrices ``dQ_T`` (k, 3, 3) that take ``anisotropy`` (k, 3, 3, Mandel) out
    of triangles ``idx``, each scaled so that ``Q_T + dQ_T >= KEEP Q_T``; ``tensors``
    (k, 3, 3) the triangles' own ``C_T`` (units of E). None where ``C_T`` is not
    positive definite (as under the paper's unstabilised couplings).

    The bound is read in strain space: ``dQ_T`` and ``Q_T`` are ``A E_T^-T (.) E_T^-1``
    of ``-anisotropy`` and ``C_T``, so their generalised eigenvalues are those of
    ``-anisotropy`` against ``C_T``."""
    c = 0.5 * (tensors + tensors.transpose(0, 2, 1))
    definite = _positive_definite(c)
    c[~definite] = np.eye(3)
    low = np.linalg.inv(np.linalg.cholesky(c))
    lam = np.linalg.eigvalsh(-low @ anisotropy @ low.transpose(0, 2, 1))[:, 0]
    factor = np.where(definite, np.minimum(1.0, (1.0 - KEEP) / np.maximum(-lam, 1e-300)), 0.0)
    e_inv = np.linalg.inv(unit_elongations(mesh, idx))
    area = _geometry.of(mesh).tri_area[idx] * factor
    dq = -area[:, None, None] * np.einsum("mki,mkl,mlj->mij", e_inv, anisotropy, e_inv)
    return 0.5 * (dq + dq.transpose(0, 2, 1))


def _positive_definite(c: np.ndarray) -> np.ndarray:
    """Sylvester's criterion for symmetric (k, 3, 3), with a relative margin, (k,) bool."""
    tol = 1e-9 * np.abs(np.trace(c, axis1=1, axis2=2))
    m1 = c[:, 0, 0]
    m2 = c[:, 0, 0] * c[:, 1, 1] - c[:, 0, 1] ** 2
    return (m1 > tol) & (m2 > tol * m1) & (np.linalg.det(c) > tol * m2)


def corrected_triangles(mesh: Mesh, cells: np.ndarray) -> np.ndarray:
    """The triangles that take the regional term: all but the exact ``cells`` and the
    slivers (:data:`~dvstatic.lattice.cells.CELL_SINE`), shape (k,) int."""
    take = _geometry.smallest_sine(_geometry.of(mesh)) >= CELL_SINE
    take[cells] = False
    return np.flatnonzero(take)
