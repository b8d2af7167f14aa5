"""The paper's closed-form calibration of ``k_n`` and ``nu_m`` from E and nu.

``"paper"`` calibration (Chaiko & Konovalov 2021): every bond is assumed to follow
the macroscopic (affine) strain; the energy of the bonds is matched to plane stress.
Under an affine strain eps a bond stretches by ``l n.eps.n`` and its dual side by
``R_e : eps``; averaging the resulting stiffness over bond directions gives::

    C1111 = 3 alpha k_n + M1 k_n nu_m,      C1122 = alpha k_n + M2 k_n nu_m,
    alpha = sum(l^2) / (8 A),
    M1 = sum l (tau + 2 rho) / (8 A),        M2 = sum l (3 tau - 2 rho) / (8 A),

with ``tau = tr R_e`` and ``rho = n.R_e.n``. DV: ``R_e = r t t`` (the side is carried
affinely), so ``tau = r``, ``rho = 0``: M1 = beta, M2 = 3 beta, beta = sum(l r) / (8 A),
the paper's eqs. (7), (9), (10). RV: ``R_e`` follows from the derivative of the
circumcentre (see docs/theory.md); ``tau = r`` still holds, ``rho != 0`` (on an
equilateral lattice ``rho = -r``, so M1 = -beta, M2 = 5 beta). Matching to plane stress
gives the paper's eqs. (19), (20), which contain (9), (10) as the DV case::

    k_n  = E (M2 - nu M1) / (alpha (1 - nu^2) (3 M2 - M1)),
    nu_m = alpha (1 - 3 nu) / (nu M1 - M2).
"""

from __future__ import annotations

import numpy as np

from ...errors import CalibrationError
from ...mesh import Mesh
from ..geometry import Geometry
from ..kinematics import half_sides
from .base import MicroParameters, Moments

__all__ = [
    "moment_sums",
    "moments_from_sums",
    "moments",
    "admissible_nu",
    "paper_from_moments",
    "paper",
]


def moment_sums(kind: str, geom: Geometry, weights=None, bond_mask=None, tri_mask=None):
    """Raw sums behind :func:`moments` over the selected bonds and triangles.

    Returns ``[sum w l^2, sum l r, S1, S2]`` (length^2), where ``S1 = M1 * 8A`` and
    ``S2 = M2 * 8A`` (for DV ``S1 = sum l r``, ``S2 = 3 sum l r``). With masks, sums
    over disjoint sets of bonds and triangles add up: that is how the distributed
    solver calibrates across ranks.
    """
    length, r = geom.length, geom.r
    w = np.ones(len(length)) if weights is None else np.asarray(weights)
    bm = slice(None) if bond_mask is None else bond_mask
    s_alpha = float(np.sum(w[bm] * length[bm] ** 2))
    s_beta = float(np.sum(length[bm] * r[bm]))
    if kind == "DV":
        return np.array([s_alpha, s_beta, s_beta, 3 * s_beta])
    x = geom.x_tri if tri_mask is None else geom.x_tri[tri_mask]
    _, dr = half_sides(x, None, grad=True)
    m = len(x)
    # R_Tk = sym(sum_v dr_v (x) x_v): linear map from a homogeneous strain to delta r_Tk
    R = np.einsum("mkvi,mvj->mkij", dr.reshape(m, 3, 3, 2), x)
    tau = R[..., 0, 0] + R[..., 1, 1]
    d = x[:, [2, 0, 1]] - x[:, [1, 2, 0]]
    ll = np.hypot(d[..., 0], d[..., 1])
    n = d / ll[..., None]
    rho = np.einsum("mki,mkij,mkj->mk", n, R, n)
    return np.array(
        [
            s_alpha,
            s_beta,
            float(np.sum(ll * (tau + 2 * rho))),
            float(np.sum(ll * (3 * tau - 2 * rho))),
        ]
    )


def moments_from_sums(sums, area: float) -> Moments:
    """:class:`Moments` from :func:`moment_sums` (added over all parts) and the area."""
    s = np.asarray(sums, dtype=float) / (8.0 * area)
    return Moments(float(s[0]), float(s[1]), float(s[2]), float(s[3]))


def paper_from_moments(kind: str, mom: Moments, E: float, nu: float) -> MicroParameters:
    """The paper's closed form (eqs. 9-10 / 19-20) for given lattice moments.

    Raises
    ------
    CalibrationError
        If nu lies outside the interval where the calibration has a solution.
    """
    lo, hi = admissible_nu(mom)
    if not (lo < nu < hi):
        raise CalibrationError(
            f"nu = {nu} has no {kind} calibration on this mesh: the accepted range is "
            f"{lo:.4g} < nu < {hi:.4g}",
            "nu",
        )
    k_n = E * (mom.m2 - nu * mom.m1) / (mom.alpha * (1 - nu**2) * (3 * mom.m2 - mom.m1))
    nu_m = mom.alpha * (1 - 3 * nu) / (nu * mom.m1 - mom.m2)
    return MicroParameters(float(k_n), float(nu_m), "paper", mom, (lo, hi))


def moments(kind: str, mesh: Mesh, geom: Geometry, weights=None) -> Moments:
    """alpha, beta, M1, M2 of ``mesh`` for model ``kind`` ("DV" or "RV").

    ``weights`` (n_bonds,) are the relative normal-spring stiffnesses (``bonds="voronoi"``);
    they enter alpha = sum w l^2 / (8 A) only, since the coupling is not weighted.
    """
    return moments_from_sums(moment_sums(kind, geom, weights), mesh.area)


def admissible_nu(mom: Moments) -> tuple[float, float]:
    """Open nu interval in (-1, 1) where the closed-form calibration gives k_n > 0.

    Returns ``(nan, nan)`` if there is none.
    """
    lo, hi = -1.0, 1.0
    den = 3 * mom.m2 - mom.m1
    if den <= 0:
        return (float("nan"), float("nan"))
    # need M2 - nu M1 > 0
    if mom.m1 > 0:
        hi = min(hi, mom.m2 / mom.m1)
    elif mom.m1 < 0:
        lo = max(lo, mom.m2 / mom.m1)
    elif mom.m2 <= 0:
        return (float("nan"), float("nan"))
    if not lo < hi:
        return (float("nan"), float("nan"))
    return (lo, hi)


def paper(
    kind: str, mesh: Mesh, geom: Geometry, E: float, nu: float, weights=None
) -> MicroParameters:
    """Closed-form calibration of the paper (eqs. 9-10 for DV, 19-20 for RV).

    Raises
    ------
    CalibrationError
        If nu lies outside the interval where the calibration has a solution.
    """
    return paper_from_moments(kind, moments(kind, mesh, geom, weights), E, nu)
