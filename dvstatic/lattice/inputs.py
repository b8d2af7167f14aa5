"""The checks of a model's material and damage arguments (:class:`~dvstatic.DV`,
:class:`~dvstatic.RV`), at the public boundary."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..errors import InputError
from ..material import Elastic

__all__ = ["checked_materials", "checked_damage", "preset_keywords", "METHODS"]

#: named presets of the model's keywords (``method=``): the paper's model, kept as the
#: paper states it whatever the defaults become
METHODS = {
    "paper": {
        "calibration": "paper",
        "bonds": "uniform",
        "boundary_cells": "lattice",
        "anisotropy": "keep",
    },
}


def preset_keywords(model) -> dict:
    """The keywords ``model.method``'s preset sets ({} without one). A keyword at its
    default takes the preset's value; one given otherwise is refused; given
    micro-parameters are kept (as ``replaced`` passes them).

    Raises
    ------
    InputError
        An unknown method, or a keyword that contradicts it.
    """
    import dataclasses

    from .._checks import check_choice
    from .calibration import MicroParameters

    if model.method is None:
        return {}
    check_choice("method", model.method, tuple(METHODS))
    defaults = {f.name: f.default for f in dataclasses.fields(model)}
    out = {}
    for name, value in METHODS[model.method].items():
        given = getattr(model, name)
        if isinstance(given, (MicroParameters, tuple)):
            continue
        if given not in (value, defaults[name]):
            raise InputError(
                f"{name}={given!r} contradicts method={model.method!r}, which is "
                f"{name}={value!r}: drop one of them",
                name,
            )
        out[name] = value
    return out


def checked_materials(materials, model) -> dict[str, Elastic]:
    """``materials`` (region name -> (E, nu) or Elastic) as Elastic in ``model.plane``,
    every region one of ``model.mesh.regions``; {} for None."""
    if materials is None:
        return {}
    if not isinstance(materials, Mapping):
        raise TypeError("materials must map region names to (E, nu)")
    out = {}
    for name, value in materials.items():
        if name not in model.mesh.regions:
            known = ", ".join(repr(k) for k in model.mesh.regions) or "none"
            raise InputError(
                f"materials: unknown region {name!r}; the mesh's regions: {known}",
                "materials",
            )
        if isinstance(value, Elastic):
            value = (value.E, value.nu)
        try:
            E, nu = value
        except (TypeError, ValueError):
            raise TypeError(f"materials[{name!r}] must be (E, nu), got {value!r}") from None
        out[str(name)] = Elastic(E, nu, model.plane)
    return out


def checked_damage(damage, closed, n_bonds: int) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Read-only copies of the bond factors ``damage`` (n_bonds,) in [0, 1] and the
    ``closed`` flags (None where no crack is closed)."""
    if damage is None:
        if closed is not None:
            raise InputError("closed applies to a damaged lattice: give damage", "closed")
        return None, None
    d = np.array(damage, dtype=float)  # a copy: the model owns it
    if d.shape != (n_bonds,):
        raise InputError(
            f"damage must have one factor per bond, shape ({n_bonds},), got {d.shape}",
            "damage",
        )
    if not np.all((d >= 0) & (d <= 1)):
        raise InputError("damage factors must lie in [0, 1] (1 intact, 0 broken)", "damage")
    d.setflags(write=False)
    if closed is None:
        return d, None
    c = np.array(closed, dtype=bool)
    if c.shape != d.shape:
        raise InputError(f"closed must have one flag per bond, got {c.shape}", "closed")
    c.setflags(write=False)
    return d, (c if c.any() else None)
