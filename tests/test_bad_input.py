"""Catalogue of bad inputs: each raises a precise ValueError/TypeError.

Each row: (id, callable, exception type, regex the message must match).
"""

import numpy as np
import pytest

import dvstatic as dv

SQ = np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]])
TRI = np.array([[0, 1, 2], [0, 2, 3]])


def _lattice():
    return dv.mesh.rectangle(1.0, 1.0, 0.25, kind="lattice")


CASES = [
    (
        "points non-finite",
        lambda: dv.Mesh(np.r_[SQ[:3], [[np.nan, 1]]], TRI),
        ValueError,
        "non-finite",
    ),
    ("points wrong shape", lambda: dv.Mesh(np.zeros((4, 3)), TRI), ValueError, r"shape \(N, 2\)"),
    ("points not numeric", lambda: dv.Mesh([["a", "b"]] * 4, TRI), TypeError, "numeric"),
    (
        "duplicate points",
        lambda: dv.Mesh(np.r_[SQ, [[1, 1.0]]], np.r_[TRI, [[1, 2, 4]]]),
        ValueError,
        "duplicate point",
    ),
    (
        "degenerate triangle",
        lambda: dv.Mesh(np.r_[SQ, [[0.5, 0.0]]], np.r_[TRI, [[0, 4, 1]]]),
        ValueError,
        "zero area",
    ),
    ("unused point", lambda: dv.Mesh(np.r_[SQ, [[5, 5.0]]], TRI), ValueError, "not used"),
    (
        "triangle index out of range",
        lambda: dv.Mesh(SQ, np.array([[0, 1, 7]])),
        ValueError,
        r"indices must be in \[0, 4\)",
    ),
    ("float triangles", lambda: dv.Mesh(SQ, TRI.astype(float)), TypeError, "integer"),
    (
        "triangles wrong shape",
        lambda: dv.Mesh(SQ, np.array([[0, 1, 2, 3]])),
        ValueError,
        r"shape \(M, 3\)",
    ),
    (
        "overlapping triangles",
        lambda: dv.Mesh(SQ, np.array([[0, 1, 2], [0, 1, 3]])),
        ValueError,
        "overlap",
    ),
    ("E zero", lambda: dv.DV(_lattice(), 0.0, 0.2), ValueError, "E must be > 0"),
    ("E negative", lambda: dv.RV(_lattice(), -1.0, 0.2), ValueError, "E must be > 0"),
    ("E not a number", lambda: dv.DV(_lattice(), "1e5", 0.2), TypeError, "E must be a real"),
    ("nu = 1", lambda: dv.DV(_lattice(), 1e5, 1.0), ValueError, "-1 < nu < 1"),
    ("nu = -1", lambda: dv.RV(_lattice(), 1e5, -1.0), ValueError, "-1 < nu < 1"),
    ("nu nan", lambda: dv.DV(_lattice(), 1e5, float("nan")), ValueError, "finite"),
    (
        "unknown calibration",
        lambda: dv.DV(_lattice(), 1e5, 0.2, calibration="magic"),
        ValueError,
        "accepted: paper",
    ),
    ("mesh not a Mesh", lambda: dv.DV(SQ, 1e5, 0.2), TypeError, "dvstatic Mesh"),
    (
        "unknown side name",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), dv.Fix("west"), []),
        ValueError,
        "unknown boundary part 'west'; known parts: 'bottom'",
    ),
    (
        "no supports",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), [], dv.Traction("right", (1, 0))),
        ValueError,
        "no supports",
    ),
    (
        "only one direction",
        lambda: dv.solve(
            dv.DV(_lattice(), 1e5, 0.2), dv.Fix("left", x=0), dv.Traction("right", (1, 0))
        ),
        ValueError,
        "translation along",
    ),
    (
        "single pinned node",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), dv.Fix([0]), dv.Traction("right", (1, 0))),
        ValueError,
        "rotation about",
    ),
    (
        "u wrong shape",
        lambda: dv.DV(_lattice(), 1e5, 0.2).internal_force(np.zeros(7)),
        ValueError,
        "must have shape",
    ),
    (
        "eps wrong shape",
        lambda: dv.homogenize(dv.DV(_lattice(), 1e5, 0.2), np.zeros(3)),
        ValueError,
        r"shape \(2, 2\)",
    ),
    ("traction value wrong", lambda: dv.Traction("right", (1, 2, 3)), ValueError, "two numbers"),
    (
        "traction on interior edge",
        lambda: dv.solve(
            dv.DV(_lattice(), 1e5, 0.2), [dv.Fix("left")], dv.Traction(np.array([[0, 6]]), (1, 0))
        ),
        ValueError,
        "not a boundary edge",
    ),
    (
        "fix node out of range",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), dv.Fix([999]), []),
        ValueError,
        r"must lie in \[0, ",
    ),
    (
        "conflicting supports",
        lambda: dv.solve(
            dv.DV(_lattice(), 1e5, 0.2), [dv.Fix("left", x=0), dv.Fix("left", x=1)], []
        ),
        ValueError,
        "conflicting supports",
    ),
    ("fix where wrong type", lambda: dv.Fix(3.5), TypeError, "part name or an index array"),
    (
        "load in supports",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), [dv.BodyForce((0, 1))], []),
        TypeError,
        "supports must be Fix",
    ),
    (
        "unknown solver",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), dv.Fix("left"), [], solver="cholesky"),
        ValueError,
        "accepted: auto",
    ),
    (
        "rtol out of range",
        lambda: dv.solve(dv.DV(_lattice(), 1e5, 0.2), dv.Fix("left"), [], rtol=2.0),
        ValueError,
        r"rtol must be in \(0, 1\)",
    ),
    (
        "rectangle h too large",
        lambda: dv.mesh.rectangle(1.0, 0.5, 0.8),
        ValueError,
        "larger than the domain",
    ),
    (
        "rectangle negative width",
        lambda: dv.mesh.rectangle(-1.0, 1.0, 0.1),
        ValueError,
        "width must be > 0",
    ),
    (
        "rectangle unknown kind",
        lambda: dv.mesh.rectangle(1, 1, 0.1, kind="hex"),
        ValueError,
        "accepted: lattice, jittered, random",
    ),
    (
        "jitter too large",
        lambda: dv.mesh.rectangle(1, 1, 0.1, jitter=0.7),
        ValueError,
        r"jitter must be in \[0, 0.5\)",
    ),
    (
        "periodic too few points",
        lambda: dv.mesh.periodic_square(5),
        ValueError,
        "n_points must be >= 16",
    ),
    (
        "perturbed negative amplitude",
        lambda: _lattice().perturbed(-0.1),
        ValueError,
        "amplitude must be >= 0",
    ),
    (
        "strain on bounded mesh",
        lambda: dv.DV(_lattice(), 1e5, 0.2).internal_force(
            np.zeros((_lattice().n_points, 2)), strain=np.eye(2)
        ),
        ValueError,
        "periodic meshes only",
    ),
]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_input(case):
    _, fn, exc, pattern = case
    with pytest.raises(exc, match=pattern):
        fn()
