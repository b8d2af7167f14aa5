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
    # (an imported mesh keeps the surface springs: compare like with like)
    with_recipe = cls(mesh, E, NU, bonds="surface").micro
    bare = cls(_bare(mesh), E, NU).micro
    # as a perturbed lattice of its local spread (before the CVT family): DV +1.20 %
    assert abs(bare.k_n / with_recipe.k_n - 1) < 0.005
    assert abs(bare.nu_m - with_recipe.nu_m) < 0.005
    assert bare.details["cvt_family_weight"] >= 0.9  # 0.95 or 1 (rounded), by the seed
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
    # a class too narrow for deep nodes counts those off the boundary, as the mesh does
    narrow = dv.mesh.rectangle(0.1, 1, 0.025, kind="lattice").points
    pts = np.unique(np.round(np.vstack([narrow, b - [0.9, 0.0]]), 9), axis=0)
    classes = spread_classes(dv.Mesh(pts, Delaunay(pts).simplices))
    assert classes.defects[np.argmin(classes.spread)] < 0.05  # with the boundary: 0.32


def test_the_curve_is_kept_per_weight():
    from dvstatic.lattice.calibration import relaxed

    mesh = _bare(dv.mesh.rectangle(2, 1, 0.04, kind="jittered", seed=2))
    cvt = relaxed("DV", mesh, E, NU, spread=0.086, defects=0.33)
    half = relaxed("DV", mesh, E, NU, spread=0.086, defects=0.165)
    lattice = relaxed("DV", mesh, E, NU, spread=0.086, defects=0.0)
    assert cvt.details["cvt_family_weight"] == 1.0 and half.details["cvt_family_weight"] == 0.5
    assert "cvt_family_weight" not in lattice.details
    assert cvt.k_n / lattice.k_n - 1 < -0.008  # the CVT family relaxes 1.1 % less
    assert half.k_n / lattice.k_n - 1 == pytest.approx(0.5 * (cvt.k_n / lattice.k_n - 1), rel=0.1)
    again = relaxed("DV", mesh, E, NU, spread=0.086, defects=0.33)
    assert again.k_n == cvt.k_n


@pytest.mark.parametrize(("name", "value"), [("spread", float("nan")), ("defects", 1.5)])
def test_bad_overrides_are_refused(name, value):
    from dvstatic.errors import CalibrationError
    from dvstatic.lattice.calibration import relaxed

    mesh = _bare(dv.mesh.rectangle(1, 1, 0.1, kind="jittered", seed=2))
    with pytest.raises(CalibrationError, match=name):
        relaxed("DV", mesh, E, NU, **{name: value})


def test_each_class_is_calibrated_with_its_own_defect_fraction():
    from scipy.spatial import Delaunay

    a = dv.mesh.rectangle(1, 1, 0.025, kind="lattice").points
    b = dv.mesh.rectangle(1, 1, 0.025, kind="random", seed=3).points + [1.0, 0.0]
    pts = np.unique(np.round(np.vstack([a, b]), 9), axis=0)
    model = dv.DV(dv.Mesh(pts, Delaunay(pts).simplices), E, NU)
    field = model.micro_field
    for (_, c), micro in field.micros.items():
        assert micro.details["defect_fraction"] == field.classes.defects[c]


def test_the_weight_has_no_jump_where_the_families_meet():
    s = np.linspace(0.25, 0.37, 241)
    w = np.array([table.family_weight(x, 0.70) for x in s])
    assert np.max(np.abs(np.diff(w))) < 0.05 and w[-1] == 0.0
