"""``criterion="mohr-coulomb"``: Coulomb's shear line with a tension cut-off on each
bond's Voronoi face."""

from __future__ import annotations

import math

import numpy as np

from ...errors import InputError
from .base import linear_factors, register
from .responses import per_bond
from .stress import Stress

__all__ = ["MohrCoulomb", "MAX_FRICTION_ANGLE", "ucs"]

#: friction angles (degrees) accepted: [0, MAX_FRICTION_ANGLE)
MAX_FRICTION_ANGLE = 70.0


def ucs(cohesion: float, friction_angle: float) -> float:
    """The continuum's uniaxial compressive strength ``2 c cos(phi) / (1 - sin(phi))``
    (stress units; ``friction_angle`` in degrees)."""
    phi = math.radians(friction_angle)
    return 2.0 * cohesion * math.cos(phi) / (1.0 - math.sin(phi))


def _angle(value, name: str) -> None:
    ok = isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)
    if not ok or not math.isfinite(float(value)) or not 0 <= value < MAX_FRICTION_ANGLE:
        raise InputError(
            f"{name} must be an angle in degrees in [0, {MAX_FRICTION_ANGLE:g}), got {value!r}",
            name,
        )


@register
class MohrCoulomb(Stress):
    """The face of bond e fails when, with ``sigma_n`` its normal stress (tension > 0)
    and ``tau`` its shear stress, either ``sigma_n = ft`` (the tension cut-off, mode
    *tension*) or ``|tau| + sigma_n tan(phi) = c`` (Coulomb's line: mode *shear* if the
    face is not in compression there, *crushing* if it is).

    ``sigma_n`` and ``tau`` are the traction of the ``stress`` criterion's unbiased patch
    stress on the face (next to damage, ``sigma_n`` from the bond's own tension, which
    resolves a crack tip). The strengths are the continuum's own: under a uniform
    stress every face carries exactly that stress's traction, so the lattice first
    fails where the continuum envelope says, on the face closest to the critical plane
    (``45 - phi / 2`` degrees from the largest compression; on a mesh with bonds in
    every direction, within the spread of their angles). Both conditions are linear in
    the load factor on each side of the shear's sign, so the factor of every bond under
    held plus growing loads has a closed form.
    """

    name = "mohr-coulomb"
    parameters = ("cohesion", "friction_angle")

    def set_parameters(self, model, ftb, factors, cohesion=None, friction_angle=None) -> None:
        missing = [
            k for k, v in (("cohesion", cohesion), ("friction_angle", friction_angle)) if v is None
        ]
        if missing:
            raise InputError(
                f"criterion 'mohr-coulomb' needs {' and '.join(missing)} (stress units; "
                "degrees in [0, 70))",
                missing[0],
            )
        f = 1.0 if factors is None else factors
        self.ft = ftb * f
        self.c = per_bond(model, cohesion, "cohesion") * f
        self.tan = np.tan(np.radians(per_bond(model, friction_angle, "friction_angle", _angle)))

    def face(self, x, w, g, intact=None) -> tuple[np.ndarray, np.ndarray]:
        """Normal and shear stress on every bond's face in state ``x``, (n_bonds,) each
        (stress units): the unbiased patch stress's traction on the face; next to damage
        the normal stress the bond's own tension stands for (as the ``stress``
        criterion, slivers excepted); a bond without a patch takes the normal stress
        its tension stands for and no shear."""
        normal, v, covered, t = self.measure(x, w, g, intact)
        n = self.n
        nx2, ny2, nxy = n[:, 0] ** 2, n[:, 1] ** 2, n[:, 0] * n[:, 1]
        sn = v[:, 0] * nx2 + v[:, 1] * ny2 + 2 * v[:, 2] * nxy
        with np.errstate(divide="ignore", invalid="ignore"):
            if intact is not None and not intact.all():
                near = self._near_damage(intact) & covered & ~self.use_tension
                sn = np.where(near, normal / self.h_nn, sn)
            sn = np.where(covered, sn, t / self.s_tension * self.ft)
        tau = v[:, 2] * (nx2 - ny2) + nxy * (v[:, 1] - v[:, 0])
        return sn, tau

    def factors(self, xh, xg, w, g, intact, threshold):
        b, q = self.face(xg, w, g, intact)
        a, p = (0.0, 0.0) if xh is None else self.face(xh, w, g, intact)
        tan = self.tan
        tests = [linear_factors(a, b, self.ft)]  # the cut-off
        for sign in (1.0, -1.0):  # Coulomb's line, either sense of the shear
            tests.append(linear_factors(sign * p + a * tan, sign * q + b * tan, self.c))
        ratio = np.stack([r for r, _ in tests])
        excess = np.stack([x for _, x in tests])
        which = np.argmax(np.where(np.any(excess >= 1.0, axis=0), excess, ratio), axis=0)
        pick = np.arange(len(b))
        r, x = ratio[which, pick], excess[which, pick]
        lam = np.where(x >= 1.0, 0.0, np.divide(1.0, r, out=np.zeros_like(r), where=r > 0))
        compressed = a + lam * b < 0
        mode = np.where(which == 0, 0, np.where(compressed, 2, 1))
        return r, x, mode
