"""The quality flags of a model's relaxed calibration: the parts of a mesh without
recipe whose micro-structure lies outside what their calibration was measured on."""

from __future__ import annotations

import logging

import numpy as np

from . import calibration

log = logging.getLogger(__name__)

__all__ = ["model_flags"]


def model_flags(model) -> tuple[calibration.QualityFlag, ...]:
    """The flags of ``model`` (a :class:`~dvstatic.lattice.models.VoronoiModel`):
    :attr:`VoronoiModel.calibration_flags`, each logged as a warning
    (the model's cached property calls this once); empty for meshes with a recipe,
    periodic meshes and given micro-parameters."""
    s = model.mesh.sampling
    if (
        not (isinstance(model.calibration, str) and model.calibration == "relaxed")
        or model.mesh.is_periodic
        or (s is not None and s.reproducible)
    ):
        return ()
    field = model.micro_field
    if field is not None:
        pair = model.material_of_triangle * field.classes.n_classes
        pair = pair + field.classes.of_triangle
        micro_of = {m * field.classes.n_classes + c: v for (m, c), v in field.micros.items()}
    else:
        pair = model.material_of_triangle
        micro_of = dict(enumerate(model.micros))
    keys = np.array(sorted(micro_of))
    details = [micro_of[k].details or {} for k in keys]
    if not all("local_spread_sample" in d for d in details):
        return ()
    idx = np.searchsorted(keys, pair)
    sample = np.array([d["local_spread_sample"] for d in details])[idx]
    asked = np.array([d.get("local_spread", d["local_spread_sample"]) for d in details])
    if field is not None:  # a class's spread is its triangles' (a selection):
        # each region is held against the sample its class was measured on
        flags = calibration.calibration_flags(model.mesh, sample)
    else:
        flags = calibration.calibration_flags(model.mesh, asked[idx], sample)
    if all("defect_fraction" in d for d in details):
        defects = np.array([d["defect_fraction"] for d in details])[idx]
        flags = flags + tuple(calibration.defect_flags(model.mesh, asked[idx], defects))
    flags = flags + tuple(calibration.anisotropy_flags(model.mesh))
    flags = flags + tuple(calibration.grading_flags(model.mesh))
    for f in flags:
        log.warning("calibration: %s", f.message())
    return flags
