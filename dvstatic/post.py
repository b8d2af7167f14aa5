"""Post-processing: stresses, energy, homogenisation, interpolation (layer 5).

Stress conventions: 2x2 Cauchy stress (force per length for unit thickness, i.e.
units of E). Mandel vectors are ``[s11, s22, sqrt(2) s12]`` (paper eq. 6), so that
``sigma = C eps`` holds with ``eps = [e11, e22, sqrt(2) e12]``; a plane-stress
material has ``C = E/(1-nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, 1-nu]]`` in this form.
(The paper prints the shear entry as ``(1-nu)/2``, i.e. ``C1212``; that is half the
Mandel entry; :func:`plane_stress_tensor` returns the Mandel form.)
"""

from __future__ import annotations

import numpy as np

from ._checks import as_displacement, as_strain, check_positive
from .errors import InputError
from .lattice import VoronoiModel, check_model
from .lattice.operator import virial_sum
from .material import SQ2, plane_stress_tensor, to_mandel
from .mesh.locate import interpolate
from .stress import bond_state, node_stress, strain_stress

__all__ = [
    "virial_stress",
    "node_stress",
    "square_stress",
    "homogenize",
    "elastic_tensor",
    "plane_stress_tensor",
    "to_mandel",
    "energy",
    "interpolate",
    "strain_stress",
]


def virial_stress(
    model: VoronoiModel, u=None, strain=None, linear: bool = False, current: bool = True
) -> np.ndarray:
    """Mean stress of the whole lattice, ``(1/A) sum_e T_e l_e n_e (x) n_e``, shape (2, 2).

    Parameters
    ----------
    model : DV or RV
    u : array_like, shape (N, 2), optional
        Displacement (zero if omitted).
    strain : (2, 2), optional
        Macroscopic strain carried by the period (periodic meshes).
    linear : bool
        Use the linearised tensions on the reference geometry.
    current : bool
        Divide by the current area (Cauchy stress) instead of the reference area.
        Ignored when ``linear`` is true.
    """
    model = check_model(model)
    if u is None:
        u = np.zeros((model.mesh.n_points, 2))
    t, d = bond_state(model, u, strain, linear)
    area = model.mesh.area
    if current and not linear:
        area = _current_area(model, u, strain)
    return virial_sum(t, d) / area


def _current_area(model: VoronoiModel, u, strain) -> float:
    u = as_displacement(u, model.mesh.n_points)
    op = model.operator
    y = op.deformed_triangles(u, op.check_strain(strain))
    a = y[:, 1] - y[:, 0]
    b = y[:, 2] - y[:, 0]
    return float(0.5 * np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]))


def square_stress(model: VoronoiModel, u, h: float, linear: bool = True):
    """The paper's h-square stress: bond forces in squares of side h.

    The bounding box is tiled with squares of side ``h``; the stress in a square is
    ``(1/h^2) sum_e T_e (length of bond e inside the square) n_e (x) n_e``, which for
    nodes in equilibrium equals the average of the forces of the bonds crossing the
    square's sides (the paper's definition). The paper's mean
    ``sigma_0 = h^2 sum sigma^h`` over a full tiling of the domain is the lattice
    virial stress.

    Returns
    -------
    centres : ndarray, shape (ny, nx, 2)
    sigma : ndarray, shape (ny, nx, 2, 2)
    covered : ndarray, shape (ny, nx) bool
        Squares entirely inside the mesh (others are cut by the boundary).
    """
    model = check_model(model)
    h = check_positive("h", h)
    t, d = bond_state(model, u, None, linear)
    mesh = model.mesh
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    nx = max(1, int(np.ceil((hi[0] - lo[0]) / h - 1e-9)))
    ny = max(1, int(np.ceil((hi[1] - lo[1]) / h - 1e-9)))
    if nx * ny > 4_000_000:
        raise InputError(
            f"h = {h} gives {nx * ny} squares; use h >= {(hi - lo).max() / 2000:.3g}", "h"
        )
    ln = np.hypot(d[:, 0], d[:, 1])
    dd = np.einsum("e,ei,ej->eij", t / ln, d, d).reshape(-1, 4)  # T n n l = (T/l) d d
    seg = model.geometry.length[:, None] * model.geometry.direction  # reference bonds
    cell, w, rep = _bond_pieces(mesh.points[mesh.topology.bonds[:, 0]], seg, lo, h, nx, ny)
    sig = np.zeros((nx * ny, 4))
    for c in range(4):
        sig[:, c] = np.bincount(cell, w * dd[rep, c], nx * ny)
    sig /= h * h
    xs = lo[0] + (np.arange(nx) + 0.5) * h
    ys = lo[1] + (np.arange(ny) + 0.5) * h
    centres = np.stack(np.meshgrid(xs, ys), axis=-1)
    tri_cell = np.clip(
        np.floor((mesh.triangle_coordinates().mean(axis=1) - lo) / h).astype(np.int64),
        0,
        [nx - 1, ny - 1],
    )
    area_in = np.bincount(tri_cell @ np.array([1, nx]), mesh.triangle_areas, nx * ny)
    covered = (area_in >= 0.999 * h * h).reshape(ny, nx)
    return centres, sig.reshape(ny, nx, 2, 2), covered


def _bond_pieces(p0: np.ndarray, seg: np.ndarray, lo, h: float, nx: int, ny: int):
    """Split every bond at the grid lines it crosses: square index, length fraction and
    bond index of every piece."""
    q0 = (p0 - lo) / h
    q1 = q0 + seg / h
    nb = len(p0)
    cuts = [np.zeros(nb), np.ones(nb)]
    for ax in range(2):
        a, c = np.minimum(q0[:, ax], q1[:, ax]), np.maximum(q0[:, ax], q1[:, ax])
        kmax = int(np.max(np.floor(c) - np.ceil(a))) + 1 if nb else 0
        base = np.ceil(a)
        for j in range(max(kmax, 0)):
            line = base + j
            with np.errstate(divide="ignore", invalid="ignore"):
                s = (line - q0[:, ax]) / (q1[:, ax] - q0[:, ax])
            cuts.append(np.where((line <= c) & np.isfinite(s), np.clip(s, 0, 1), 1.0))
    s = np.sort(np.stack(cuts, axis=1), axis=1)
    ds = np.diff(s, axis=1)
    mid = 0.5 * (s[:, 1:] + s[:, :-1])
    pts = q0[:, None, :] + mid[..., None] * (q1 - q0)[:, None, :]
    ix = np.clip(np.floor(pts[..., 0]).astype(np.int64), 0, nx - 1)
    iy = np.clip(np.floor(pts[..., 1]).astype(np.int64), 0, ny - 1)
    return (iy * nx + ix).ravel(), ds.ravel(), np.repeat(np.arange(nb), ds.shape[1])


def homogenize(model: VoronoiModel, eps, linear: bool = False) -> np.ndarray:
    """Mean stress of the lattice under the homogeneous strain ``eps``, shape (2, 2).

    Every node is moved by ``x' = (I + eps) x`` (on a periodic mesh the period is
    deformed likewise), the bond forces are evaluated on the deformed geometry and
    the mean (Cauchy) stress ``(1/A') sum T l' n' (x) n'`` is returned, ``A'`` the
    deformed area. With ``linear=True`` the linearised model is used instead (no
    geometric non-linearity; reference area).

    Parameters
    ----------
    model : DV or RV
    eps : array_like, shape (2, 2)
        Displacement gradient imposed on every node (symmetric for a pure strain).
    """
    model = check_model(model)
    eps = as_strain(eps)
    mesh = model.mesh
    u = mesh.points @ eps.T
    strain = eps if mesh.is_periodic else None
    return virial_stress(model, u, strain, linear=linear, current=True)


def elastic_tensor(model: VoronoiModel) -> np.ndarray:
    """Small-strain elasticity matrix of the lattice under affine strain, Mandel (3, 3).

    Columns are the Mandel stresses for the unit Mandel strains
    ``e11``, ``e22`` and ``sqrt(2) e12`` imposed on every node (paper exp. 1),
    computed with the linearised model (exact small-strain limit). Compare with
    :func:`plane_stress_tensor`.
    """
    model = check_model(model)
    probes = [
        np.array([[1.0, 0.0], [0.0, 0.0]]),
        np.array([[0.0, 0.0], [0.0, 1.0]]),
        np.array([[0.0, 1.0], [1.0, 0.0]]) / SQ2,
    ]
    cols = [to_mandel(homogenize(model, e, linear=True)) for e in probes]
    return np.stack(cols, axis=1)


def energy(model: VoronoiModel, u) -> float:
    """Strain energy of the linear model, ``u.K.u / 2`` (energy per unit thickness)."""
    return check_model(model).energy(u)
