"""Post-processing: bond tensions, stresses, energy, homogenisation.

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
from .models import VoronoiModel

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

SQ2 = np.sqrt(2.0)


def _check_model(model) -> VoronoiModel:
    if not isinstance(model, VoronoiModel):
        raise TypeError(f"model must be a dvstatic DV or RV model, got {type(model).__name__}")
    return model


def to_mandel(sigma: np.ndarray) -> np.ndarray:
    """Mandel vector(s) ``[s11, s22, sqrt(2) s12]`` of (..., 2, 2) tensors, shape (..., 3)."""
    s = np.asarray(sigma, dtype=float)
    return np.stack(
        [s[..., 0, 0], s[..., 1, 1], SQ2 * 0.5 * (s[..., 0, 1] + s[..., 1, 0])], axis=-1
    )


def plane_stress_tensor(E: float, nu: float) -> np.ndarray:
    """Plane-stress elasticity matrix in Mandel form, shape (3, 3) (units of E)."""
    E = check_positive("E", E)
    c = E / (1.0 - nu**2)
    return c * np.array([[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, 1.0 - nu]])


def _bond_state(model: VoronoiModel, u, strain, linear: bool):
    """Tensions, current bond vectors (E, 2)."""
    if linear:
        t = model.linear_tension(u, strain)
        d = model.geometry.length[:, None] * model.geometry.direction
        return t, d
    u = as_displacement(u, model.mesh.n_points)
    s = model._strain(strain)
    t, d, _ = model._tension(u, s)
    return t, d


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
    model = _check_model(model)
    if u is None:
        u = np.zeros((model.mesh.n_points, 2))
    t, d = _bond_state(model, u, strain, linear)
    ln = np.hypot(d[:, 0], d[:, 1])
    s = np.einsum("e,ei,ej->ij", t / ln, d, d)
    area = model.mesh.area
    if current and not linear:
        area = _current_area(model, u, strain)
    return s / area


def _current_area(model: VoronoiModel, u, strain) -> float:
    u = as_displacement(u, model.mesh.n_points)
    s = model._strain(strain)
    y = model._triangles_now(u, s)
    a = y[:, 1] - y[:, 0]
    b = y[:, 2] - y[:, 0]
    return float(0.5 * np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]))


def node_stress(model: VoronoiModel, u, linear: bool = True) -> np.ndarray:
    """Virial stress of every particle over its Voronoi cell, shape (N, 2, 2).

    ``sigma_i = (1 / A_i) sum_{bonds at i} (1/2) T l n (x) n``, with ``A_i`` the Voronoi
    cell area (the one-third-of-triangles area where the Voronoi cell of a boundary
    node degenerates). Cell averages weighted by area reproduce
    :func:`virial_stress` exactly; on boundary nodes the value is the mean over the
    truncated cell.
    """
    model = _check_model(model)
    t, d = _bond_state(model, u, None, linear)
    ln = np.hypot(d[:, 0], d[:, 1])
    half = 0.5 * (t / ln)[:, None, None] * d[:, :, None] * d[:, None, :]
    b = model.mesh.topology.bonds
    n = model.mesh.n_points
    out = np.zeros((n, 4))
    hv = half.reshape(-1, 4)
    for c in range(4):
        out[:, c] = np.bincount(b[:, 0], hv[:, c], n) + np.bincount(b[:, 1], hv[:, c], n)
    g = model.geometry
    area = np.where(g.cell_area > 0.25 * g.dual_area, g.cell_area, g.dual_area)
    return (out / area[:, None]).reshape(n, 2, 2)


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
    model = _check_model(model)
    h = check_positive("h", h)
    t, d = _bond_state(model, u, None, linear)
    mesh = model.mesh
    b = mesh.topology.bonds
    p0 = mesh.points[b[:, 0]]
    lo = mesh.points.min(axis=0)
    hi = mesh.points.max(axis=0)
    nx = max(1, int(np.ceil((hi[0] - lo[0]) / h - 1e-9)))
    ny = max(1, int(np.ceil((hi[1] - lo[1]) / h - 1e-9)))
    if nx * ny > 4_000_000:
        raise ValueError(f"h = {h} gives {nx * ny} squares; use h >= {(hi - lo).max() / 2000:.3g}")
    seg = model.geometry.length[:, None] * model.geometry.direction  # reference bond vectors
    ln = np.hypot(d[:, 0], d[:, 1])
    coef = t / ln  # T n n l_inside = (T / l) d d (l_inside / l)
    dd = np.einsum("e,ei,ej->eij", coef, d, d).reshape(-1, 4)
    # split each bond at the grid lines it crosses; parameters s in [0, 1]
    q0 = (p0 - lo) / h
    q1 = q0 + seg / h
    cuts = [np.zeros(len(b)), np.ones(len(b))]
    for ax in range(2):
        a, c = np.minimum(q0[:, ax], q1[:, ax]), np.maximum(q0[:, ax], q1[:, ax])
        kmax = int(np.max(np.floor(c) - np.ceil(a))) + 1 if len(b) else 0
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
    cell = (iy * nx + ix).ravel()
    w = ds.ravel()
    sig = np.zeros((nx * ny, 4))
    rep = np.repeat(np.arange(len(b)), ds.shape[1])
    for c in range(4):
        sig[:, c] = np.bincount(cell, w * dd[rep, c], nx * ny)
    sig /= h * h
    xs = lo[0] + (np.arange(nx) + 0.5) * h
    ys = lo[1] + (np.arange(ny) + 0.5) * h
    centres = np.stack(np.meshgrid(xs, ys), axis=-1)
    area_in = np.bincount(
        np.clip(
            np.floor((mesh.triangle_coordinates().mean(axis=1) - lo) / h).astype(np.int64),
            0,
            [nx - 1, ny - 1],
        )
        @ np.array([1, nx]),
        mesh.triangle_areas,
        nx * ny,
    )
    covered = (area_in >= 0.999 * h * h).reshape(ny, nx)
    return centres, sig.reshape(ny, nx, 2, 2), covered


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
    model = _check_model(model)
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
    model = _check_model(model)
    probes = [
        np.array([[1.0, 0.0], [0.0, 0.0]]),
        np.array([[0.0, 0.0], [0.0, 1.0]]),
        np.array([[0.0, 1.0], [1.0, 0.0]]) / SQ2,
    ]
    cols = [to_mandel(homogenize(model, e, linear=True)) for e in probes]
    return np.stack(cols, axis=1)


def energy(model: VoronoiModel, u) -> float:
    """Strain energy of the linear model, ``u.K.u / 2`` (energy per unit thickness)."""
    model = _check_model(model)
    u = as_displacement(u, model.mesh.n_points).reshape(-1)
    return float(0.5 * u @ (model._stiffness_bsr @ u))


def interpolate(mesh, field, points) -> np.ndarray:
    """Linear (P1) interpolation of a nodal field at arbitrary points inside the mesh.

    Parameters
    ----------
    mesh : Mesh
    field : array_like, shape (N,) or (N, k)
        Nodal values (e.g. ``sol.u``).
    points : array_like, shape (n, 2)

    Returns
    -------
    ndarray, shape (n,) or (n, k)

    Raises
    ------
    ValueError
        If a point lies outside the mesh.
    """
    from scipy.spatial import cKDTree

    f = np.asarray(field, dtype=float)
    p = np.atleast_2d(np.asarray(points, dtype=float))
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"points must have shape (n, 2), got {p.shape}")
    if f.shape[0] != mesh.n_points:
        raise ValueError(f"field must have {mesh.n_points} rows, got {f.shape[0]}")
    x = mesh.triangle_coordinates()
    tree = cKDTree(x.mean(axis=1))
    tri_idx = np.full(len(p), -1)
    bary = np.zeros((len(p), 3))
    todo = np.arange(len(p))
    k = min(8, mesh.n_triangles)
    while todo.size:
        _, cand = tree.query(p[todo], k=k)
        cand = cand.reshape(len(todo), -1)
        a = x[cand, 1] - x[cand, 0]
        b = x[cand, 2] - x[cand, 0]
        q = p[todo, None, :] - x[cand, 0]
        det = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
        l1 = (q[..., 0] * b[..., 1] - q[..., 1] * b[..., 0]) / det
        l2 = (a[..., 0] * q[..., 1] - a[..., 1] * q[..., 0]) / det
        lam = np.stack([1 - l1 - l2, l1, l2], axis=-1)
        inside = np.all(lam >= -1e-10, axis=-1)
        found = inside.any(axis=1)
        j = np.argmax(inside, axis=1)
        rows = np.flatnonzero(found)
        tri_idx[todo[rows]] = cand[rows, j[rows]]
        bary[todo[rows]] = lam[rows, j[rows]]
        todo = todo[~found]
        if k >= mesh.n_triangles:
            break
        k = min(4 * k, mesh.n_triangles)
    if np.any(tri_idx < 0):
        bad = p[tri_idx < 0][0]
        raise ValueError(f"point {bad.tolist()} lies outside the mesh")
    vals = f[mesh.triangles[tri_idx]]  # (n, 3, ...)
    return np.einsum("nv,nv...->n...", bary, vals)


def strain_stress(model: VoronoiModel, u) -> np.ndarray:
    """Kinematic stress recovery: plane-stress law applied to the lattice strain.

    The displacement is interpolated linearly on each triangle, the triangle strains
    are averaged to the nodes (weighted by triangle area) and mapped through the
    plane-stress law of the model's E and nu. Unlike the virial (force-based) stress,
    this does not see the extra force the paper's uniform ``k_n`` puts into the
    surface bonds (about 1.7x the true stress parallel to a free edge of a lattice), so
    it is the better estimate of surface stresses such as stress concentrations.

    Returns
    -------
    ndarray, shape (N, 2, 2)
    """
    model = _check_model(model)
    mesh = model.mesh
    u = as_displacement(u, mesh.n_points)
    x = model.geometry.x_tri
    ut = u[mesh.triangles]
    a, b = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    det = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    # gradients of the barycentric functions 1 and 2
    g1 = np.c_[b[:, 1], -b[:, 0]] / det[:, None]
    g2 = np.c_[-a[:, 1], a[:, 0]] / det[:, None]
    du1, du2 = ut[:, 1] - ut[:, 0], ut[:, 2] - ut[:, 0]
    grad = du1[:, :, None] * g1[:, None, :] + du2[:, :, None] * g2[:, None, :]  # (M, 2, 2)
    eps = 0.5 * (grad + grad.transpose(0, 2, 1))
    area = model.geometry.tri_area
    n = mesh.n_points
    acc = np.zeros((n, 4))
    w = np.zeros(n)
    for v in range(3):
        idx = mesh.triangles[:, v]
        w += np.bincount(idx, area, n)
        for c in range(4):
            acc[:, c] += np.bincount(idx, area * eps.reshape(-1, 4)[:, c], n)
    e = (acc / w[:, None]).reshape(n, 2, 2)
    E, nu = model.E, model.nu
    c = E / (1 - nu**2)
    tr = e[:, 0, 0] + e[:, 1, 1]
    s = np.empty_like(e)
    s[:, 0, 0] = c * (e[:, 0, 0] + nu * e[:, 1, 1])
    s[:, 1, 1] = c * (e[:, 1, 1] + nu * e[:, 0, 0])
    s[:, 0, 1] = s[:, 1, 0] = E / (1 + nu) * e[:, 0, 1]
    del tr
    return s
