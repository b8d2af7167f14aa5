"""Bond strengths from a material tensile strength, random strength fields and the
saw-tooth softening that gives each bond a fracture energy.

Strength (why this relation)
----------------------------
A bond breaks when its tension reaches its strength ``s_e``. We ask that a lattice
under *uniform* stress fail when the largest principal stress reaches ``ft``. The
tension of a bond is linear in the applied stress: applying the three unit uniform
stresses as boundary tractions ``sigma . n`` to the body itself (a self-equilibrated
load; three solves with one factorisation) gives ``T_e = H_e : sigma`` with ``H_e`` a
symmetric 2x2 tensor per bond. The largest tension a uniaxial stress of magnitude ``ft``
can give the bond is ``ft lambda_max(H_e)``, reached when the stress runs along the
eigenvector of ``H_e`` (close to the bond's direction), so::

    s_e = ft * lambda_max(H_e).

Under any uniform stress with largest principal stress ``ft`` no bond exceeds its
strength, and the bonds aligned with it reach it: the first break comes at ``ft``
exactly, on any mesh, for DV and RV, in plane stress and plane strain. The closed form
of an *affine* lattice (DV: ``s_e = ft/E* (k_e l_e - nu* g r_e)``) ignores the
non-affine relaxation of irregular meshes and the surface layer; measured on a 2 x 1
plate at 996 nodes its first break came at 0.50 ft (DV) and 0.44 ft (RV), which is why
the relaxed response is used.

Random strength
---------------
``Weibull(m, length, seed)`` multiplies the strengths by a Weibull variable of modulus
``m`` with mean one, correlated over ``length`` through a Gaussian copula (a Gaussian
field with covariance ``exp(-r^2 / (2 length^2))`` from random Fourier features, mapped
to the Weibull distribution by its quantile function); ``length = 0`` draws independent
values per bond.

Softening
---------
With a fracture energy ``gf`` (energy per unit crack area), a bond whose strength is
reached does not vanish at once: it follows a saw-tooth approximation of a linear
softening law from its crack (elongation ``delta_p``, force ``k delta_p``) to zero force
at ``delta_u``, in ``teeth`` steps spaced half logarithmically, half linearly in the
elongation (:func:`teeth_at`: no tooth takes much of the bond's stiffness or force at
once); after the last tooth the bond is removed. Breaking at tooth ``i`` releases
``k (d_i - d_{i+1}) delta_i^2 / 2``; ``delta_u`` is solved per bond so that the teeth
release exactly ``(pi / 4) gf t r_e``: the fracture energy of the bond's Voronoi face
(side ``r_e``, thickness ``t``) times the mean projection of a face on a straight crack
(Buffon: a crack of length ``L`` cuts faces of total length ``4 L / pi`` on average).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = [
    "Weibull",
    "uniform_stress_loads",
    "principal_response",
    "bond_strength",
    "weibull_factors",
    "teeth_at",
    "smallest_gf",
]

#: share of the logarithmic part in the spacing of the saw-tooth steps (:func:`teeth_at`,
#: whose stated bounds are those of one half)
_SPACING = 0.5
#: relative excess of a bond's fracture energy over its elastic energy at the crack below
#: which the teeth cannot be told apart in floating point: such a bond breaks at once
MIN_EXCESS = 1e-9


@dataclass(frozen=True)
class Weibull:
    """A random strength field: Weibull modulus ``m`` (> 0; larger is less scattered),
    correlation ``length`` (length units, 0 for independent bonds) and ``seed``."""

    m: float
    length: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        def real(v) -> bool:
            return isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)

        if not (real(self.m) and self.m >= 1):
            raise InputError(
                f"weibull m must be a finite number >= 1 (strength scatter: m = 12 is about "
                f"10 %, m = 24 about 5 %), got {self.m!r}",
                "weibull.m",
            )
        if not (real(self.length) and self.length >= 0):
            raise InputError(
                f"weibull length must be a finite number >= 0 (0: independent bonds), got "
                f"{self.length!r}",
                "weibull.length",
            )
        if (
            not isinstance(self.seed, numbers.Integral)
            or isinstance(self.seed, bool)
            or (self.seed < 0)
        ):
            raise InputError(
                f"weibull seed must be an integer >= 0, got {self.seed!r}", "weibull.seed"
            )
        object.__setattr__(self, "m", float(self.m))
        object.__setattr__(self, "length", float(self.length))
        object.__setattr__(self, "seed", int(self.seed))


def uniform_stress_loads(mesh, thickness: float) -> list[np.ndarray]:
    """Nodal forces (2N,) of the unit uniform stresses xx, yy, xy as boundary tractions."""
    be = mesh.boundary_edges
    x = mesh.points
    d = x[be[:, 1]] - x[be[:, 0]]
    nl = np.stack([d[:, 1], -d[:, 0]], 1)
    # make the normals outward: sum over edges of x (x) n L is +area I for outward n
    if np.trace(np.einsum("ei,ej->ij", x[be].mean(1), nl)) < 0:
        nl = -nl
    out = []
    for sig in ([[1.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [0.0, 1.0]], [[0.0, 1.0], [1.0, 0.0]]):
        F = 0.5 * thickness * nl @ np.array(sig).T
        f = np.zeros((mesh.n_points, 2))
        for c in range(2):
            f[:, c] = np.bincount(be.ravel(), np.repeat(F[:, c], 2), mesh.n_points)
        out.append(f.reshape(-1))
    return out


def principal_response(tensions: list[np.ndarray]) -> np.ndarray:
    """``lambda_max(H_e)`` (n_bonds,) from the tensions under unit xx, yy and xy stress
    (the xy case applies ``sigma_xy = sigma_yx = 1``, so its tension is ``2 H_xy``)."""
    a, b, c = tensions
    return 0.5 * (a + b) + np.sqrt(0.25 * (a - b) ** 2 + 0.25 * c**2)


def weibull_factors(midpoints: np.ndarray, field: Weibull, modes: int = 400) -> np.ndarray:
    """Mean-one Weibull factors (n,) at ``midpoints`` (n, 2) (see the module notes)."""
    from scipy.special import gamma, ndtr

    rng = np.random.default_rng(field.seed)
    n = len(midpoints)
    if field.length > 0:
        k = rng.normal(scale=1.0 / field.length, size=(modes, 2))
        phase = rng.uniform(0, 2 * np.pi, modes)
        z = np.sqrt(2.0 / modes) * np.cos(midpoints @ k.T + phase).sum(axis=1)
    else:
        z = rng.standard_normal(n)
    p = np.clip(ndtr(z), 1e-300, 1 - 1e-16)
    w = (-np.log1p(-p)) ** (1.0 / field.m)
    return w / gamma(1.0 + 1.0 / field.m)


def bond_strength(principal: np.ndarray, ft_bond: np.ndarray, factors=None) -> np.ndarray:
    """Strength (n_bonds,) (force units): ``ft * lambda_max(H_e)`` times random factors.

    Raises
    ------
    InputError
        If a bond cannot be loaded in tension by any uniform stress (lambda_max <= 0).
    """
    s = ft_bond * principal
    if factors is not None:
        s = s * factors
    if not np.all(s > 0):
        e = int(np.flatnonzero(~(s > 0))[0])
        raise InputError(
            f"bond {e} takes no tension under any uniform stress (lambda_max = "
            f"{principal[e]:.3g}): the mesh has a degenerate triangle there",
            "mesh",
        )
    return s


def _tooth_openings(ratio: np.ndarray, n_teeth: int) -> np.ndarray:
    """Elongations of the teeth over the crack elongation, ``x_i`` in [1, ``ratio``):
    the roots of ``psi(x) = i / n`` (closed form through the Wright omega function; the
    linear limit ``1 + (R - 1) i / n`` for ``R`` within 1e-6 of 1)."""
    from scipy.special import wrightomega

    ratio = np.asarray(ratio, float)[:, None]
    level = np.arange(n_teeth)[None, :] / n_teeth
    near_one = ratio - 1.0 < 1e-6
    r = np.where(near_one, 2.0, ratio)
    a = _SPACING / np.log(r)
    b = (1.0 - _SPACING) / (r - 1.0)
    x = (a / b) * np.real(wrightomega(np.log(b / a) + (level + b) / a))
    x = np.where(near_one, 1.0 + (ratio - 1.0) * level, np.minimum(x, ratio))
    x[:, 0] = 1.0
    return x


def _teeth_energy(ratio: np.ndarray, n_teeth: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Teeth of bonds with ``delta_u / delta_p = ratio``: spring factors, elongations
    over ``delta_p``, and the release over ``k delta_p^2 / 2``."""
    x = _tooth_openings(ratio, n_teeth)
    r = np.asarray(ratio, float)[:, None]
    d = (r - x) / ((r - 1.0) * x)
    dnext = np.concatenate([d[:, 1:], np.zeros((len(d), 1))], axis=1)
    return d, x, np.sum((d - dnext) * x**2, axis=1)


def teeth_at(spring, peak, energy, n_teeth: int = 30):
    """Saw-tooth steps of bonds that crack at elongation ``peak``.

    The teeth peak on the linear softening line from ``(delta_p, k delta_p)`` to
    ``(delta_u, 0)``; tooth ``i`` (0 the crack itself) at the elongation ``delta_i =
    delta_p x_i`` where ``psi(x_i) = i / n``, with (``R = delta_u / delta_p``)::

        psi(x) = ln(x) / (2 ln R) + (x - 1) / (2 (R - 1)),

    half logarithmic, half linear: every tooth opens the bond by at most a factor
    ``R^(2/n)`` further than the one before, and successive tooth peaks differ in force
    by at most ``2 k delta_p / n``. (Equal force steps alone put the first tooth at
    ``delta_p + (delta_u - delta_p) / n``: with the ``R`` of about 30-95 of the notched
    beam's bonds (h = 10-5 mm) the bond lost 49-76 % of its stiffness at once, its load
    went to its neighbours, and a band of barely softened bonds grew with mesh
    refinement: the beam released 1.26 x Gf x ligament at h = 5 mm.) The spring factor
    of tooth ``i`` is the secant ``d_i = force_i / (k delta_i)``; after the last tooth
    the bond is removed. Breaking at tooth ``i`` releases ``k (d_i - d_{i+1}) delta_i^2 /
    2``; ``delta_u`` is solved (bisection) so that the teeth release ``energy``.

    Parameters
    ----------
    spring, peak, energy : ndarray, shape (n,)
        Spring stiffness (force / length), elongation at the crack (length, > 0) and the
        energy to release (force x length, > ``spring * peak^2 / 2``).
    n_teeth : int
        Number of teeth (>= 2).

    Returns
    -------
    d : ndarray, shape (n, n_teeth)
        Spring factors, ``d[:, 0] = 1``.
    delta : ndarray, shape (n, n_teeth)
        Elongation at which each tooth breaks.

    Raises
    ------
    ValueError
        If an ``energy`` is not above the elastic energy ``spring * peak^2 / 2`` (by a
        relative :data:`MIN_EXCESS`).
    """
    k, dp, target = (np.atleast_1d(np.asarray(a, float)) for a in (spring, peak, energy))
    tau = target / (0.5 * k * dp**2)
    if not np.all(tau > 1.0 + MIN_EXCESS):
        e = int(np.argmin(np.where(np.isnan(tau), -np.inf, tau)))
        raise ValueError(
            f"energy {target[e]:.4g} of bond {e} must exceed its elastic energy at the "
            f"crack, spring * peak^2 / 2 = {0.5 * k[e] * dp[e] ** 2:.4g}, by a relative "
            f"{MIN_EXCESS:g}"
        )
    lo, hi = np.full_like(tau, 1.0), np.maximum(4.0 * tau, 2.0)
    for _ in range(200):
        short = _teeth_energy(hi, n_teeth)[2] < tau
        if not np.any(short):
            break
        hi = np.where(short, 2.0 * hi, hi)
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        short = _teeth_energy(mid, n_teeth)[2] < tau
        lo, hi = np.where(short, mid, lo), np.where(short, hi, mid)
        if np.array_equal(lo, hi):  # collapsed onto one number: no later step moves it
            break
    d, x, _ = _teeth_energy(0.5 * (lo + hi), n_teeth)
    return d, dp[:, None] * x


def smallest_gf(strength, spring, face, thickness) -> np.ndarray:
    """The fracture energy below which a bond would release less than it stores at its
    strength (a snap-back of the bond alone), per bond: ``s^2 / (2 k t r_e)``."""
    return 0.5 * np.asarray(strength) ** 2 / (np.asarray(spring) * thickness * np.asarray(face))
