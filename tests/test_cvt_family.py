"""Meshes without recipe between the perturbed lattices and the CVT family
(dvstatic.lattice.calibration: ``defect_fraction``, ``table.family_weight``): a
CVT-like mesh is calibrated as CVT, a lattice-like one as a perturbed lattice."""

import numpy as np
import pytest

import dvstatic as dv
from dvstatic.lattice.calibration import table
from dvstatic.lattice.calibration.relaxed import defect_fraction, local_spread
from dvstatic.mesh import periodic_sample
from dvstatic.mesh.recipe import Sampling

E, NU = 1e4, 0.3


def _bare(mesh):
    return dv.Mesh(mesh.points, mesh.triangles, parts=mesh.parts)


def test_defect_fraction_of_the_families():
    assert defect_fraction(periodic_sample(Sampling("lattice"), 2000, 0)) == 0.0
    lattice = periodic_sample(Sampling("lattice", perturbations=(0.1,)), 2000, 0)
    assert defect_fraction(lattice) == 0.0  # small moves flip no bond
    assert abs(defect_fraction(periodic_sample(Sampling("random"), 5000, 0)) - 0.70) < 0.02
    rect = dv.mesh.rectangle(2, 1, 0.02, kind="random", seed=1)
    assert abs(defect_fraction(rect) - 0.70) < 0.03  # its interior, off the boundary rows


def test_family_weight_places_a_micro_structure_between_the_families():
    fam = table.load()["cvt_family"]
    s, d = fam["spread"][8], fam["defects"][8]  # CVT, 120 Lloyd iterations
    assert table.family_weight(s, d) == pytest.approx(1.0)
    assert table.family_weight(s, 0.0) == 0.0  # a perturbed lattice of that spread
    assert 0.4 < table.family_weight(s, 0.5 * d) < 0.6
    fam_random = (max(fam["spread"]), fam["defects"][int(np.argmax(fam["spread"]))])
    assert table.family_weight(*fam_random) == 0.0  # random points: the families meet


@pytest.mark.parametrize("cls", [dv.DV, dv.RV])
def test_a_cvt_mesh_stripped_of_its_recipe_calibrates_as_with_it(cls):
    mesh = dv.mesh.rectangle(2, 1, 0.02, kind="cvt", seed=2)
    with_recipe, bare = cls(mesh, E, NU).micro, cls(_bare(mesh), E, NU).micro
    # as a perturbed lattice of its local spread (before the CVT family): DV +1.20 %
    assert abs(bare.k_n / with_recipe.k_n - 1) < 0.005
    assert abs(bare.nu_m - with_recipe.nu_m) < 0.005
    assert bare.details["cvt_family_weight"] == 1.0
    assert bare.details["defect_fraction"] > 0.3


def test_a_lattice_like_mesh_keeps_the_perturbed_lattice():
    mesh = _bare(dv.mesh.rectangle(2, 1, 0.02, kind="jittered", seed=2))
    micro = dv.DV(mesh, E, NU).micro
    assert "cvt_family_weight" not in micro.details
    assert micro.details["defect_fraction"] == 0.0
    assert micro.details["local_spread"] == pytest.approx(local_spread(mesh))


def test_classes_carry_their_defect_fraction():
    from scipy.spatial import Delaunay

    from dvstatic.lattice.calibration import spread_classes

    a = dv.mesh.rectangle(1, 1, 0.025, kind="lattice").points
    b = dv.mesh.rectangle(1, 1, 0.025, kind="random", seed=3).points + [1.0, 0.0]
    pts = np.unique(np.round(np.vstack([a, b]), 9), axis=0)
    classes = spread_classes(dv.Mesh(pts, Delaunay(pts).simplices))
    lo, hi = np.argmin(classes.spread), np.argmax(classes.spread)
    assert classes.defects[lo] < 0.05 and classes.defects[hi] > 0.5
