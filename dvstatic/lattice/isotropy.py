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
micro-structure), and takes out the regional mean's anisotropy at the window's scale
(a second pass of the same average still finds part of it: what varies within a
window).

Where the term would soften a triangle below half of its own bond matrix (``Q_T +
dQ_T`` not above ``Q_T / 2``: :data:`KEEP`) it is scaled down, so every triangle stays
positive definite (its lowest eigenvalue at least halved); exact cells (already
isotropic), slivers (:data:`~dvstatic.lattice.cells.CELL_SINE`) and patches of random
points take no term and no part in the averages.

Default (``"auto"``, :func:`default_anisotropy`) where it was measured to help: meshes
without a generator recipe (imported; gmsh plates, rings and Cook's membranes:
validation/imported.py) and the generators' graded CVT meshes (the tunnel example at
h_near = 0.0125, seeds 0-3: wall hoop rms 1.77 -> 0.85 %, worst node 4.5 -> 2.3 %, with
their fabric springs). Not on the package's uniform meshes, isotropic by construction,
where a region's anisotropy is noise that the relaxation does not follow (Lame at 2e4
nodes, two seeds: jittered L2 0.100 -> 0.097 % but bore worst node 0.41 -> 0.62 %;
random points L2 0.61 -> 1.26 %), nor on graded random points (tunnel wall rms 3.8 ->
6.0 % with the surface springs), nor, within any mesh, on patches of random points
(:data:`RANDOM_SPREAD`).
"""

from __future__ import annotations

import numpy as np

from ..mesh import Mesh
from . import geometry as _geometry
from .calibration.descriptors import ring_mean, spread_field
from .cells import CELL_SINE, unit_elongations

__all__ = [
    "ANISOTROPY",
    "REGION_RINGS",
    "KEEP",
    "RANDOM_SPREAD",
    "corrected_triangles",
    "default_anisotropy",
    "resolve_anisotropy",
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
#: triangles whose local spread (over 4 rings) is larger take no term: random points
#: (0.26-0.44, 0.1 to 99.9 percentiles), where a region's anisotropy is noise that the
#: relaxation does not follow (a disc of random points in a lattice came out 8.6 % stiff
#: with it); CVT 0.06-0.16, lattices jittered by 0.3 0.11-0.22 (0.45: 0.16-0.30), gmsh
#: cells up to 0.09
RANDOM_SPREAD = 0.25

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
    """The anisotropic part of the regional mean tensor of every triangle of
    ``lattice``, shape (M, 3, 3) (zero elsewhere).

    Parameters
    ----------
    mesh : Mesh
    tensors : ndarray, shape (M, 3, 3)
        Every triangle's tensor (Mandel, units of E).
    lattice : ndarray of int, shape (k,)
        The triangles that take the term (:func:`corrected_triangles`); a region is
        averaged over these alone: the exact cells are isotropic by construction,
        slivers' near-singular tensors (up to 1 / sine^2) and random points' noise
        would swamp their neighbours'.
    material : ndarray of int, shape (M,), optional
        Every triangle's material: a region is averaged within its triangle's
        material (a stiff inclusion's anisotropy is not a soft matrix's).
    rings : int
        Passes of the neighbour average.
    """
    take = np.zeros(len(tensors), dtype=bool)
    take[lattice] = True
    material = np.zeros(len(tensors), dtype=np.int64) if material is None else material
    dev = tensors - isotropic_part(tensors)
    out = np.zeros_like(dev)
    for k in np.unique(material[take]):
        mine = take & (material == k)
        node, touched = _node_means(mesh, dev, mine)
        node = ring_mean(mesh, node * touched[:, None], rings)
        node /= np.maximum(ring_mean(mesh, touched, rings), 1e-300)[:, None]
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
    """Bond matrices ``dQ_T`` (k, 3, 3) that take ``anisotropy`` out of triangles
    ``idx``, each scaled so that ``Q_T + dQ_T >= KEEP Q_T``; none where ``C_T`` is not
    positive definite (as under the paper's unstabilised couplings).

    Parameters
    ----------
    mesh : Mesh
    idx : ndarray of int, shape (k,)
        The triangles (:func:`corrected_triangles`).
    anisotropy : ndarray, shape (k, 3, 3)
        Their regional anisotropy (:func:`regional_anisotropy`; Mandel, units of E).
    tensors : ndarray, shape (k, 3, 3)
        Their own tensors ``C_T`` (Mandel, units of E).

    Notes
    -----
    The bound is read in strain space: ``dQ_T`` and ``Q_T`` are ``A E_T^-T (.) E_T^-1``
    of ``-anisotropy`` and ``C_T``, so their generalised eigenvalues are those of
    ``-anisotropy`` against ``C_T``.
    """
    c = 0.5 * (tensors + tensors.transpose(0, 2, 1))
    definite = _positive_definite(c)
    c[~definite] = np.eye(3)
    chol_inv = np.linalg.inv(np.linalg.cholesky(c))
    lam = np.linalg.eigvalsh(-chol_inv @ anisotropy @ chol_inv.transpose(0, 2, 1))[:, 0]
    factor = np.where(definite, np.minimum(1.0, (1.0 - KEEP) / np.maximum(-lam, 1e-300)), 0.0)
    e_inv = np.linalg.inv(unit_elongations(mesh, idx))
    area = _geometry.of(mesh).tri_area[idx] * factor
    dq = -area[:, None, None] * (e_inv.transpose(0, 2, 1) @ anisotropy @ e_inv)
    return 0.5 * (dq + dq.transpose(0, 2, 1))


def _positive_definite(c: np.ndarray) -> np.ndarray:
    """Sylvester's criterion for symmetric (k, 3, 3), with a relative margin, (k,) bool."""
    tol = 1e-9 * np.abs(np.trace(c, axis1=1, axis2=2))
    m1 = c[:, 0, 0]
    m2 = c[:, 0, 0] * c[:, 1, 1] - c[:, 0, 1] ** 2
    return (m1 > tol) & (m2 > tol * m1) & (np.linalg.det(c) > tol * m2)


def corrected_triangles(mesh: Mesh, cells: np.ndarray) -> np.ndarray:
    """The triangles that take the regional term, shape (k,) int: all but the exact
    ``cells``, the slivers (:data:`~dvstatic.lattice.cells.CELL_SINE`) and patches of
    random points (a local spread over 4 rings above :data:`RANDOM_SPREAD`)."""
    take = _geometry.smallest_sine(_geometry.of(mesh)) >= CELL_SINE
    take &= spread_field(mesh, 4)[mesh.triangles].mean(axis=1) <= RANDOM_SPREAD
    take[cells] = False
    return np.flatnonzero(take)
