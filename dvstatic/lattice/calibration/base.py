"""Calibrated micro-parameters and the lattice moments they come from."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import InputError

__all__ = ["Moments", "MicroParameters", "CALIBRATIONS"]

#: calibrations the models accept by name
CALIBRATIONS = ("relaxed", "paper")


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
    details : dict, optional
        How the values were obtained (source, sample, evaluations, seconds, ...).
    stabilised : bool
        The coupling of every triangle is clipped so that the triangle stays positive
        definite (:mod:`dvstatic.lattice.stabilise`); the relaxed calibration's values
        hold for the clipped lattice.
    """

    k_n: float
    nu_m: float
    calibration: str
    moments: Moments | None = None
    nu_range: tuple[float, float] = (float("nan"), float("nan"))
    details: dict | None = None
    stabilised: bool = False

    def __post_init__(self) -> None:
        if not (np.isfinite(self.k_n) and self.k_n > 0):
            raise InputError(f"k_n must be finite and > 0, got {self.k_n}", "k_n")
        if not np.isfinite(self.nu_m):
            raise InputError(f"nu_m must be finite, got {self.nu_m}", "nu_m")
