"""The energy each bond's saw-tooth steps release: from ``gf`` for a crack in tension,
from ``gf_shear`` for a face failing in shear or crushing (see :mod:`.strength` and
docs/fracture.md)."""

from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import InputError
from .criteria import REGISTRY, per_bond
from .strength import smallest_gf

__all__ = ["BUFFON", "GF_SHEAR_RATIO", "fracture_energies", "shear_energies", "face_of"]

#: a straight crack of length L cuts bonds whose Voronoi faces add up to 4 L / pi on
#: average (Buffon: sum_e r_e l_e |sin theta_e| / A with sum_e r_e l_e = 2 A and the mean
#: |sin| 2 / pi): each bond gets this share of gf times its face
BUFFON = np.pi / 4
#: ``gf_shear`` when it is not given, in units of ``gf``: the mode II fracture energy of
#: concrete and rock is often taken as ten times the mode I one (interface and cohesive
#: crack models of concrete, e.g. Carol, Prat & Lopez 1997; measured ratios run from
#: about 10 to 25)
GF_SHEAR_RATIO = 10.0


def shear_energies(model, criterion: str, gf, gf_shear):
    """Energy each bond's teeth release when its face fails in shear or crushing
    (force x length; None: brittle), from ``gf_shear`` or its default
    :data:`GF_SHEAR_RATIO` x ``gf``.

    Raises
    ------
    InputError
        ``gf_shear`` for a criterion without shear failure, or a negative one.
    """
    if not REGISTRY[criterion].shear:
        if gf_shear is not None:
            raise InputError(
                f"gf_shear is the fracture energy of faces failing in shear or crushing: "
                f"criterion {criterion!r} fails faces in tension only; give "
                "criterion='mohr-coulomb' or leave gf_shear out",
                "gf_shear",
            )
        return None
    if gf_shear is None:
        if gf is None:
            return None
        gfs = GF_SHEAR_RATIO * per_bond(model, gf, "gf")  # gf checked under its own name
    else:
        gfs = per_bond(model, gf_shear, "gf_shear", _non_negative)
    if not np.any(gfs > 0):
        return None
    return BUFFON * gfs * model.t * face_of(model)


def _non_negative(value, name: str) -> None:
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if not ok or not math.isfinite(float(value)) or value < 0:
        raise InputError(
            f"{name} must be a finite number >= 0 (0: brittle faces), got {value!r}", name
        )


def face_of(model) -> np.ndarray:
    """The crack face of every bond: its Voronoi side (bounded below on obtuse
    triangles)."""
    geo = model.geometry
    return np.maximum(geo.r, 0.2 * geo.length)


def fracture_energies(model, gf, s_tension) -> np.ndarray:
    """Energy each bond's teeth release (force x length), see :mod:`.strength`.

    Raises
    ------
    InputError
        If ``gf`` is too small for the mesh (a bond would snap back on its own).
    """
    face = face_of(model)
    gfb = per_bond(model, gf, "gf")
    need = smallest_gf(s_tension, model.operator.spring, face, model.t)
    if np.any(gfb <= need):
        e = int(np.argmax(need / gfb))
        raise InputError(
            f"gf = {gfb[e]:.4g} is too small for this mesh: bond {e} would store more "
            f"elastic energy at its strength than gf gives its face; use gf > "
            f"{float(np.max(need)):.4g} or a finer mesh (the bound is about "
            "ft^2 h / (2 E) and falls with the bond length h)",
            "gf",
        )
    return BUFFON * gfb * model.t * face
