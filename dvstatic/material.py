"""Plane elasticity laws and the Mandel tensor form (no dependency on meshes).

:class:`Elastic` is an isotropic material in a plane problem: plane stress, or plane
strain through the standard effective constants ``E* = E / (1 - nu^2)``,
``nu* = nu / (1 - nu)`` (the in-plane law of plane strain is the plane-stress law of
``E*, nu*``; the out-of-plane stress is ``szz = nu (sxx + syy)``).

Stress/strain matrices follow the paper's eq. (6): Mandel vectors
``[s11, s22, sqrt(2) s12]``, so that ``sigma = C eps`` holds with
``eps = [e11, e22, sqrt(2) e12]``; plane stress then reads
``E/(1-nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, 1-nu]]``. (The paper prints the shear
entry as ``(1-nu)/2``, i.e. ``C1212``, half the Mandel entry.)
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ._checks import check_choice, check_positive, check_real
from .errors import InputError

log = logging.getLogger(__name__)
#: values of nu >= 0.5 warned about (once each)
_WARNED: set[float] = set()

__all__ = [
    "PLANES",
    "Elastic",
    "SQ2",
    "to_mandel",
    "plane_stress_tensor",
    "lame_plane_stress",
    "check_poisson",
    "plane_stress_from_strain",
]

SQ2 = np.sqrt(2.0)
#: plane problems
PLANES = ("stress", "strain")


@dataclass(frozen=True)
class Elastic:
    """An isotropic elastic material of a plane problem.

    Parameters
    ----------
    E : float
        Young's modulus (force per area), > 0.
    nu : float
        Poisson's ratio: -1 < nu < 1 in plane stress, -1 < nu < 0.5 in plane strain.
    plane : {"stress", "strain"}
    """

    E: float
    nu: float
    plane: str = "stress"

    def __post_init__(self) -> None:
        object.__setattr__(self, "E", check_positive("E", self.E))
        check_choice("plane", self.plane, PLANES)
        if self.plane == "stress":
            nu = check_poisson(self.nu)
            if nu >= 0.5 and nu not in _WARNED:
                _WARNED.add(nu)
                log.warning(
                    "nu = %g in plane stress: no isotropic 3-D material has nu >= 0.5 (its "
                    "bulk modulus would be negative); a 2-D sheet law only",
                    nu,
                )
        else:
            nu = check_real("nu", self.nu)
            if not -1.0 < nu < 0.5:
                raise InputError(
                    f"nu must lie in the plane-strain range -1 < nu < 0.5, got {nu}", "nu"
                )
        object.__setattr__(self, "nu", nu)

    @property
    def in_plane(self) -> tuple[float, float]:
        """``(E*, nu*)``: the constants of the equivalent plane-stress law."""
        if self.plane == "stress":
            return self.E, self.nu
        return self.E / (1.0 - self.nu**2), self.nu / (1.0 - self.nu)

    @property
    def out_of_plane(self) -> float:
        """``sigma_zz / (sigma_xx + sigma_yy)``: 0 in plane stress, ``nu`` in plane
        strain (the principal stress normal to the plane that a 3-D strength criterion
        sees)."""
        return 0.0 if self.plane == "stress" else self.nu

    def stress(self, eps: np.ndarray) -> np.ndarray:
        """In-plane stress of strains (..., 2, 2)."""
        E2, nu2 = self.in_plane
        return plane_stress_from_strain(eps, E2, nu2)


def check_poisson(nu, name: str = "nu") -> float:
    """A Poisson's ratio in the plane-stress range ``-1 < nu < 1``."""
    v = check_real(name, nu)
    if not -1.0 < v < 1.0:
        raise InputError(f"{name} must lie in the plane-stress range -1 < nu < 1, got {v}", name)
    return v


def to_mandel(sigma: np.ndarray) -> np.ndarray:
    """Mandel vector(s) ``[s11, s22, sqrt(2) s12]`` of (..., 2, 2) tensors, shape (..., 3)."""
    s = np.asarray(sigma, dtype=float)
    return np.stack(
        [s[..., 0, 0], s[..., 1, 1], SQ2 * 0.5 * (s[..., 0, 1] + s[..., 1, 0])], axis=-1
    )


def plane_stress_tensor(E: float, nu: float) -> np.ndarray:
    """Plane-stress elasticity matrix in Mandel form, shape (3, 3) (units of E)."""
    E = check_positive("E", E)
    nu = check_poisson(nu)
    c = E / (1.0 - nu**2)
    return c * np.array([[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, 1.0 - nu]])


def lame_plane_stress(E: float, nu: float) -> tuple[float, float]:
    """Plane-stress Lame constants ``lambda* = E nu / (1 - nu^2)``, ``mu = E / (2 (1 + nu))``.

    (scikit-fem's ``lame_parameters`` returns the plane-strain / 3-D ``lambda``.)
    """
    E = check_positive("E", E)
    nu = check_poisson(nu)
    return E * nu / (1.0 - nu**2), E / (2.0 * (1.0 + nu))


def plane_stress_from_strain(eps: np.ndarray, E: float, nu: float) -> np.ndarray:
    """Plane-stress law applied to strains ``eps`` of shape (..., 2, 2), same shape."""
    c = E / (1 - nu**2)
    s = np.empty_like(eps)
    s[..., 0, 0] = c * (eps[..., 0, 0] + nu * eps[..., 1, 1])
    s[..., 1, 1] = c * (eps[..., 1, 1] + nu * eps[..., 0, 0])
    s[..., 0, 1] = s[..., 1, 0] = E / (1 + nu) * 0.5 * (eps[..., 0, 1] + eps[..., 1, 0])
    return s
