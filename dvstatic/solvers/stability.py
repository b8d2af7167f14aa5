"""Stability of a lattice: the admissible nu_m (and nu) interval for a mesh and supports.

``K = k_n (K0 + nu_m K1)`` with ``K0`` the normal springs and ``K1`` the Voronoi
coupling. With rigid motions removed (by the supports, or by pinning three dofs),
``K`` is positive definite iff ``1 + nu_m lambda > 0`` for every generalised
eigenvalue ``lambda`` of ``K1 v = lambda K0 v``, i.e. iff
``-1 / lambda_max < nu_m < -1 / lambda_min``.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from ..lattice import LatticeOperator, VoronoiModel, calibration, check_model
from ..problem import constraints

log = logging.getLogger(__name__)

__all__ = [
    "StabilityReport",
    "stability",
    "stiffness_parts",
    "nu_of_nu_m",
    "DENSE_MAX_DOF",
    "CHECK_MAX_DOF",
]

#: free dofs up to which the generalised eigenvalues are computed densely
DENSE_MAX_DOF = 2500
#: ``dv.solve`` checks positive definiteness for systems up to this many dofs
#: (free with the direct solver: the factorisation's inertia; one extra
#: factorisation with AMG); above, CG's negative-curvature test is the only check
CHECK_MAX_DOF = 200_000


@dataclass(frozen=True)
class StabilityReport:
    """Result of :func:`stability`.

    Attributes
    ----------
    lambda_min, lambda_max : float
        Extreme generalised eigenvalues of ``K1 v = lambda K0 v``. For a stabilised
        lattice (the relaxed calibration), those of its actual coupling relative to
        its springs: every nu_m is admissible there, and ``margin = 1 + lambda_min``.
    nu_m_range : (float, float)
        Open interval of ``nu_m`` for which the stiffness is positive definite.
    nu_range : (float, float)
        The corresponding interval of nu for the model's calibration (intersected
        with the calibration's own range).
    nu_m : float
        The model's value; ``stable`` tells whether it lies in ``nu_m_range``.
    margin : float
        ``min(1 + nu_m lambda)``: the smallest eigenvalue of ``K`` relative to ``K0``
        (> 0 stable).
    min_eigenvalue : float
        Eigenvalue of the model's constrained ``K`` nearest to zero (units of E).
    seconds : float
    method : str
        "dense" or "arpack".
    """

    lambda_min: float
    lambda_max: float
    nu_m_range: tuple[float, float]
    nu_range: tuple[float, float]
    nu_m: float
    stable: bool
    margin: float
    min_eigenvalue: float
    seconds: float
    method: str

    def __str__(self) -> str:
        return (
            f"admissible nu_m in ({self.nu_m_range[0]:.4g}, {self.nu_m_range[1]:.4g}), "
            f"i.e. nu in ({self.nu_range[0]:.4g}, {self.nu_range[1]:.4g}); model nu_m = "
            f"{self.nu_m:.4g}: {'stable' if self.stable else 'UNSTABLE'} "
            f"(margin {self.margin:.3g})"
        )


def stiffness_parts(model: VoronoiModel):
    """K0 (springs, k_n = 1) and K1 (coupling per unit nu_m) as CSR matrices."""
    bary = model.barycentric_images
    K0 = LatticeOperator(model.mesh, model.bond_weight, 0.0, bary).stiffness_bsr.tocsr()
    K1 = LatticeOperator(model.mesh, model.bond_weight, 1.0, bary).stiffness_bsr.tocsr()
    return K0, K1 - K0


def _free_dofs(model: VoronoiModel, supports) -> np.ndarray:
    n = 2 * model.mesh.n_points
    dofs = np.zeros(0, dtype=np.int64)
    if supports is not None:
        dofs, _ = constraints(model.mesh, supports)
    if dofs.size == 0 or model.mesh.is_periodic:
        # remove rigid motions: pin node 0 and the y dof of the node farthest from it
        p = model.mesh.points
        far = int(np.argmax(np.hypot(*(p - p[0]).T)))
        extra = [0, 1, 2 * far + 1] if not model.mesh.is_periodic else [0, 1]
        dofs = np.union1d(dofs, extra)
    keep = np.ones(n, dtype=bool)
    keep[dofs] = False
    return np.flatnonzero(keep)


def nu_of_nu_m(model: VoronoiModel, nu_m: float) -> float:
    """Poisson's ratio the model's calibration assigns to ``nu_m`` (inverse map)."""
    micro = model.micro
    if micro.calibration == "paper" and micro.moments is not None:
        m = micro.moments
        den = nu_m * m.m1 + 3 * m.alpha
        return float((m.alpha + nu_m * m.m2) / den) if den != 0 else float("inf")
    if micro.calibration == "relaxed":
        curve, _ = calibration.moduli_curve(model.kind, model.mesh, model.bonds)
        return curve(nu_m)[0]
    return float("nan")


def stability(model: VoronoiModel, supports=None) -> StabilityReport:
    """Admissible nu_m and nu interval of ``model`` on its mesh with ``supports``.

    Parameters
    ----------
    model : DV or RV
    supports : Fix or list of Fix, optional
        Without supports (or on periodic meshes) rigid motions are removed by
        pinning three dofs, which leaves the generalised eigenvalues unchanged.

    Returns
    -------
    StabilityReport

    Notes
    -----
    Cost: dense eigenvalues up to :data:`DENSE_MAX_DOF` free dofs; above, two ARPACK
    runs (largest and smallest algebraic) with one sparse factorisation of ``K0``,
    plus one shift-invert run for the smallest eigenvalue of ``K``.
    """
    check_model(model)
    t0 = time.perf_counter()
    free = _free_dofs(model, supports)
    if any(m.stabilised for m in model.micros):
        return _stabilised_report(model, free, t0)
    K0, K1 = stiffness_parts(model)
    A = K1[free][:, free]
    B = K0[free][:, free]
    A = 0.5 * (A + A.T)
    K = model.k_n * (B + model.nu_m * A)
    lam_min, lam_max, min_eig, method = _extreme_eigenvalues(A, B, K)
    hi = -1.0 / lam_min if lam_min < 0 else np.inf
    lo = -1.0 / lam_max if lam_max > 0 else -np.inf
    nu_m = model.nu_m
    rep = StabilityReport(
        lam_min,
        lam_max,
        (float(lo), float(hi)),
        _nu_interval(model, lo, hi),
        float(nu_m),
        bool(lo < nu_m < hi),
        float(min(1 + nu_m * lam_min, 1 + nu_m * lam_max)),
        min_eig,
        time.perf_counter() - t0,
        method,
    )
    log.info("stability: %s", rep)
    return rep


def _stabilised_report(model: VoronoiModel, free: np.ndarray, t0: float) -> StabilityReport:
    """A stabilised lattice is positive definite for every nu_m (each triangle is): the
    report gives the eigenvalues of its actual coupling relative to its springs."""
    op = model.operator
    Ks = LatticeOperator(model.mesh, op.spring, 0.0, model.barycentric_images).stiffness_bsr
    K = op.stiffness_bsr.tocsr()[free][:, free]
    B = Ks.tocsr()[free][:, free]
    A = K - B
    A = 0.5 * (A + A.T)
    lam_min, lam_max, min_eig, method = _extreme_eigenvalues(A, B, K)
    rep = StabilityReport(
        lam_min,
        lam_max,
        (-np.inf, np.inf),
        tuple(float(v) for v in model.micro.nu_range),
        float(model.nu_m),
        bool(1 + lam_min > 0),
        float(1 + lam_min),
        min_eig,
        time.perf_counter() - t0,
        method,
    )
    log.info("stability (stabilised coupling): %s", rep)
    return rep


def _extreme_eigenvalues(A, B, K) -> tuple[float, float, float, str]:
    """Extreme generalised eigenvalues of ``A v = lambda B v`` and the eigenvalue of
    ``K`` nearest to zero (dense for small systems, ARPACK above)."""
    import scipy.linalg
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    n = A.shape[0]
    if n <= DENSE_MAX_DOF:
        lam = scipy.linalg.eigh(A.toarray(), B.toarray(), eigvals_only=True)
        ev = np.linalg.eigvalsh(K.toarray())
        min_eig = float(ev[np.argmin(np.abs(ev))]) if np.all(ev > 0) else float(ev[0])
        return float(lam[0]), float(lam[-1]), min_eig, "dense"
    Binv = spla.splu(sp.csc_matrix(B), permc_spec="MMD_AT_PLUS_A")
    Minv = spla.LinearOperator(B.shape, matvec=Binv.solve, dtype=float)
    opts = dict(k=1, M=B, Minv=Minv, tol=1e-6, maxiter=20 * n)
    lam_max = float(spla.eigsh(A, which="LA", return_eigenvectors=False, **opts)[0])
    lam_min = float(spla.eigsh(A, which="SA", return_eigenvectors=False, **opts)[0])
    try:
        min_eig = float(spla.eigsh(K, k=1, sigma=0.0, which="LM", return_eigenvectors=False)[0])
    except (RuntimeError, spla.ArpackNoConvergence):
        min_eig = float("nan")
    return lam_min, lam_max, min_eig, "arpack"


def _nu_interval(model: VoronoiModel, lo: float, hi: float) -> tuple[float, float]:
    """The nu interval that the calibration maps the nu_m interval (lo, hi) to."""
    cal_lo, cal_hi = (-1.0, 1.0)
    if model.micro.calibration == "paper" and model.micro.nu_range:
        cal_lo, cal_hi = model.micro.nu_range
    # nu grows with nu_m for both calibrations; clip to the calibration's own range
    nu_lo = nu_of_nu_m(model, lo) if np.isfinite(lo) else cal_lo
    nu_hi = nu_of_nu_m(model, hi) if np.isfinite(hi) else cal_hi
    nu_lo = max(nu_lo, cal_lo) if np.isfinite(nu_lo) else float("nan")
    nu_hi = min(nu_hi, cal_hi) if np.isfinite(nu_hi) else float("nan")
    if np.isfinite(nu_lo) and np.isfinite(nu_hi) and nu_lo >= nu_hi:
        return float("nan"), float("nan")  # no admissible nu maps back through the calibration
    return float(nu_lo), float(nu_hi)
