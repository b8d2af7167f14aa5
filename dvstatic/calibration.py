"""Micro-parameters ``k_n`` and ``nu_m`` from the macroscopic E and nu.

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

from dataclasses import dataclass

import numpy as np

from .geometry import Geometry
from .kinematics import half_sides
from .mesh import Mesh

__all__ = ["MicroParameters", "Moments", "moments", "paper", "admissible_nu", "CALIBRATIONS"]

CALIBRATIONS = ("paper",)


@dataclass(frozen=True)
class Moments:
    """Lattice moments of a mesh for one model (dimensionless)."""

    alpha: float
    beta: float
    m1: float
    m2: float


@dataclass(frozen=True)
class MicroParameters:
    """Calibrated micro-parameters.

    Attributes
    ----------
    k_n : float
        Bond stiffness (force per length per unit thickness, i.e. units of E).
    nu_m : float
        Voronoi coupling coefficient (dimensionless).
    calibration : str
    moments : Moments
    nu_range : tuple of float
        Open interval of nu for which this calibration has a solution on this mesh.
    """

    k_n: float
    nu_m: float
    calibration: str
    moments: Moments
    nu_range: tuple[float, float]


def moments(kind: str, mesh: Mesh, geom: Geometry) -> Moments:
    """alpha, beta, M1, M2 of ``mesh`` for model ``kind`` ("DV" or "RV")."""
    area = mesh.area
    alpha = float(np.sum(geom.length**2) / (8 * area))
    beta = float(np.sum(geom.length * geom.r) / (8 * area))
    if kind == "DV":
        return Moments(alpha, beta, beta, 3 * beta)
    x = geom.x_tri
    _, dr = half_sides(x, None, grad=True)
    m = len(x)
    # R_Tk = sym(sum_v dr_v (x) x_v): linear map from a homogeneous strain to delta r_Tk
    R = np.einsum("mkvi,mvj->mkij", dr.reshape(m, 3, 3, 2), x)
    tau = R[..., 0, 0] + R[..., 1, 1]
    d = x[:, [2, 0, 1]] - x[:, [1, 2, 0]]
    ll = np.hypot(d[..., 0], d[..., 1])
    n = d / ll[..., None]
    rho = np.einsum("mki,mkij,mkj->mk", n, R, n)
    m1 = float(np.sum(ll * (tau + 2 * rho)) / (8 * area))
    m2 = float(np.sum(ll * (3 * tau - 2 * rho)) / (8 * area))
    return Moments(alpha, beta, m1, m2)


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


def paper(kind: str, mesh: Mesh, geom: Geometry, E: float, nu: float) -> MicroParameters:
    """Closed-form calibration of the paper (eqs. 9-10 for DV, 19-20 for RV).

    Raises
    ------
    ValueError
        If nu lies outside the interval where the calibration has a solution.
    """
    mom = moments(kind, mesh, geom)
    lo, hi = admissible_nu(mom)
    if not (lo < nu < hi):
        raise ValueError(
            f"nu = {nu} has no {kind} calibration on this mesh: the accepted range is "
            f"{lo:.4g} < nu < {hi:.4g}"
        )
    k_n = E * (mom.m2 - nu * mom.m1) / (mom.alpha * (1 - nu**2) * (3 * mom.m2 - mom.m1))
    nu_m = mom.alpha * (1 - 3 * nu) / (nu * mom.m1 - mom.m2)
    return MicroParameters(float(k_n), float(nu_m), "paper", mom, (lo, hi))
