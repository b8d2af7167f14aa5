"""The event loop's screen (``dvstatic.crack.criteria.screen``): an event evaluates only
the bonds that can be critical, and finds what evaluating every bond finds."""

import numpy as np
import pytest
import scipy.sparse as sp
from test_fracture import FT, NU, E, plate, pulled

import dvstatic as dv
from dvstatic.crack.criteria import criterion_for
from dvstatic.crack.criteria import screen as screen_mod
from dvstatic.crack.criteria.stress import Stress
from dvstatic.crack.criteria.tension import BondTension
from dvstatic.lattice.damage import split
from dvstatic.linalg import DirectSolver, nested_dissection


def notched(h=0.05, kind="cvt"):
    """A 2 x 0.5 beam with a notch at midspan, three-point bending by a prescribed
    deflection (the crack runs up from the notch)."""
    verts = [(0, 0), (0.98, 0), (0.98, 0.15), (1.02, 0.15), (1.02, 0), (2, 0), (2, 0.5), (0, 0.5)]
    mesh = dv.mesh.polygon(verts, h, seed=0, kind=kind)
    top = int(np.argmin(np.hypot(mesh.points[:, 0] - 1.0, mesh.points[:, 1] - 0.5)))
    sup = [dv.Fix(at=(0, 0), x=0, y=0), dv.Fix(at=(2, 0), y=0), dv.Fix([top], y=-1.0)]
    return mesh, sup


@pytest.fixture
def screens(monkeypatch):
    """Every Screen the runs of a test make; they screen at every event they can (on
    these small meshes the damage soon passes REFRESH, and they would evaluate every
    bond: the answer must not depend on it)."""
    monkeypatch.setattr(screen_mod, "REFRESH", 1.0)
    monkeypatch.setattr(screen_mod, "MIN_BONDS", 0)
    made = []
    init = screen_mod.Screen.__init__

    def keep(self, *a, **k):
        init(self, *a, **k)
        made.append(self)

    monkeypatch.setattr(screen_mod.Screen, "__init__", keep)
    return made


def unscreened(monkeypatch, *classes):
    for cls in classes:
        monkeypatch.setattr(cls, "lipschitz", lambda self: None)


def same_events(a, b):
    assert [e.bond for e in a.events] == [e.bond for e in b.events]
    assert [e.tooth for e in a.events] == [e.tooth for e in b.events]
    la = np.array([e.load_factor for e in a.events])
    lb = np.array([e.load_factor for e in b.events])
    np.testing.assert_allclose(la, lb, rtol=1e-12)


# ------------------------------------------------------------------ the pieces
def test_local_measures_are_the_whole_lattice_sums_to_the_last_bit():
    model = dv.DV(plate(0.06, kind="cvt"), E=E, nu=NU)
    sp_, geo = split(model), model.geometry
    rng = np.random.default_rng(0)
    u = rng.normal(size=2 * model.mesh.n_points)
    d = np.where(rng.uniform(size=model.mesh.n_bonds) < 0.05, 0.3, 1.0)
    w, g = sp_.factors(d)
    intact = np.all(d[sp_.tri_bonds] >= 1.0, axis=1).astype(float)
    length, area = geo.tri_l, geo.tri_area * model.t
    f = sp_.forces(u, w, g)
    t = sp_.tension(u, w, g, f)
    s, covered = sp_.patch_voigt(u, w, g, length, area, intact, f)
    bonds = rng.choice(model.mesh.n_bonds, 200, replace=False)
    tl, sl, cl = sp_.local_measures(u, w, g, length, area, intact, bonds)
    assert np.array_equal(tl, t[bonds])
    assert np.array_equal(sl, s[bonds])
    assert np.array_equal(cl, covered[bonds])
    for name in ("stress", "bond-tension"):
        crit = criterion_for(name, model, sp_)
        crit.prepare(model, FT, None, {})
        assert np.array_equal(crit(u, w, g, intact, bonds), crit(u, w, g, intact)[bonds])


def test_the_lipschitz_bound_holds_for_every_undamaged_bond():
    """|v_e(x + du) - v_e(x)| <= L_e max over the patch of |B_T du|_inf, for random
    changes and the two linear criteria; and the bound is not vacuous (within 50x on a
    random change, its worst case)."""
    model = dv.DV(plate(0.08, kind="random"), E=E, nu=NU)
    sp_ = split(model)
    w, g, intact = sp_.w, sp_.g, np.ones(len(sp_.g))
    rng = np.random.default_rng(1)
    at_node = sp_._at_node
    for name in ("stress", "bond-tension"):
        crit = criterion_for(name, model, sp_)
        crit.prepare(model, FT, None, {})
        lip = crit.lipschitz()
        for _ in range(3):
            x, du = rng.normal(size=(2, 2 * model.mesh.n_points))
            moved = np.abs(crit(x + du, w, g, intact) - crit(x, w, g, intact))
            tri = sp_.triangle_change(du)
            node = np.array([tri[at_node[i].indices].max() for i in range(model.mesh.n_points)])
            patch = np.maximum(node[sp_.ends[:, 0]], node[sp_.ends[:, 1]])
            assert np.all(moved <= lip * patch * (1 + 1e-9) + 1e-12)
            assert np.median(moved / (lip * patch)) > 0.02


def test_the_block_bound_covers_every_patch():
    """The blocks' bound of a bond's largest elongation change is at least the change
    over its own patch."""
    model = dv.DV(plate(0.05, kind="cvt"), E=E, nu=NU)
    sp_ = split(model)
    scr = screen_mod.Screen(sp_, model.mesh.points, np.ones(sp_.n_bonds), 1e-9)
    du = np.random.default_rng(2).normal(size=2 * model.mesh.n_points)
    du[: model.mesh.n_points] *= 50.0  # uneven: some blocks move far more
    tri = sp_.triangle_change(du)
    at_node = sp_._at_node
    node = np.array([tri[at_node[i].indices].max() for i in range(model.mesh.n_points)])
    patch = np.maximum(node[sp_.ends[:, 0]], node[sp_.ends[:, 1]])
    bound = scr._block_change(tri)[scr.bond_block]
    assert np.all(bound >= patch)
    bonds = np.random.default_rng(3).choice(sp_.n_bonds, 100, replace=False)
    assert np.array_equal(sp_.patch_max(tri, bonds), patch[bonds])


def test_apply_columns_gives_the_solutions_as_rows():
    model = dv.DV(plate(0.1), E=E, nu=NU)
    mesh = model.mesh
    K = sp.csr_matrix(model.stiffness()) + sp.eye(2 * mesh.n_points) * 1e-3 * E
    o = nested_dissection(mesh.points, mesh.topology.bonds)
    engine = DirectSolver(K, order=np.stack([2 * o, 2 * o + 1], axis=1).ravel())
    u = sp.random(2 * mesh.n_points, 3, density=0.01, random_state=0, format="csc")
    rows = engine.apply_columns(u)
    np.testing.assert_allclose(rows, engine.apply(u.toarray()).T, rtol=1e-10, atol=1e-12)
    out = np.empty((3, 2 * mesh.n_points))
    assert engine.apply_columns(u, out=out) is out


# ------------------------------------------------------------------ the events
def test_a_screened_run_breaks_what_an_unscreened_one_breaks(monkeypatch, screens):
    mesh, sup = notched()
    model = dv.DV(mesh, E=E, nu=NU)
    kw = dict(ft=FT, gf=5e-4, max_events=250, stop_load_ratio=0.0)
    fast = dv.fracture(model, sup, None, **kw)
    (scr,) = screens
    assert scr.screened > 0.8 * len(fast.events)
    unscreened(monkeypatch, Stress)
    slow = dv.fracture(model, sup, None, **kw)
    assert len(screens) == 1  # the second run evaluated every bond
    same_events(fast, slow)


def test_screened_runs_with_held_loads_and_the_tension_criterion(monkeypatch, screens):
    model = dv.DV(plate(0.06, kind="cvt"), E=E, nu=NU)
    sup, loads = pulled()
    kw = dict(ft=FT, gf=5e-4, max_events=30, stop_load_ratio=0.0)
    runs = [
        dict(held=[dv.Traction("top", (0.0, 0.3 * FT)), dv.Traction("bottom", (0.0, -0.3 * FT))]),
        dict(criterion="bond-tension", weibull=dv.Weibull(12, 0.2, seed=3)),
    ]
    fast = [dv.fracture(model, sup, loads, **kw, **run) for run in runs]
    assert all(s.screened > 0.8 * len(a.events) for s, a in zip(screens, fast, strict=True))
    unscreened(monkeypatch, Stress, BondTension)
    for run, a in zip(runs, fast, strict=True):
        same_events(a, dv.fracture(model, sup, loads, **kw, **run))


def test_a_screened_run_with_closing_cracks(monkeypatch, screens):
    """Contact (closed cracks carry compression) switches springs back on: the bonds
    next to them are evaluated at every event."""
    mesh, sup = notched(0.06)
    model = dv.DV(mesh, E=E, nu=NU)
    kw = dict(ft=FT, gf=5e-4, max_events=120, stop_load_ratio=0.0, contact=True)
    fast = dv.fracture(model, sup, None, **kw)
    unscreened(monkeypatch, Stress)
    same_events(fast, dv.fracture(model, sup, None, **kw))


def test_the_screen_finds_every_near_critical_bond_of_states_far_from_its_reference(
    monkeypatch,
):
    """Against every bond evaluated: states that move the most loaded region away from
    the reference's (smooth random strain fields), random strengths; every bond within
    0.1 % of the largest ratio comes out exact, and the critical one is the same."""
    from dvstatic.crack.criteria.base import TIE, _first_of_largest, linear_factors

    monkeypatch.setattr(screen_mod, "REFRESH", 1.0)
    monkeypatch.setattr(screen_mod, "MIN_BONDS", 0)
    model = dv.DV(plate(0.04, kind="cvt"), E=E, nu=NU)
    sp_ = split(model)
    crit = criterion_for("stress", model, sp_)
    thr, _ = crit.prepare(model, FT, dv.Weibull(12, 0.2, seed=5), {})
    scr = crit.screen
    assert scr is not None
    w, g, intact = sp_.w, sp_.g, np.ones(len(sp_.g))
    xy = model.mesh.points
    rng = np.random.default_rng(7)

    def field():
        c = rng.normal(size=(2, 6))
        basis = np.stack(
            [
                xy[:, 0],
                xy[:, 1],
                xy[:, 0] ** 2,
                xy[:, 0] * xy[:, 1],
                xy[:, 1] ** 2,
                np.sin(3 * xy[:, 0]),
            ],
            axis=1,
        )
        return (basis @ c.T).ravel() * 1e-4

    x0 = field()
    scr.factors(crit, None, x0, w, g, intact, thr, np.ones(len(thr), bool), 0.0)
    assert scr.full == 1
    for k in range(20):
        x = x0 + (0.05 + 0.1 * k) * field()
        ratio, _ = scr.factors(crit, None, x, w, g, intact, thr, np.ones(len(thr), bool), 0.0)
        full, _ = linear_factors(0.0, crit(x, w, g, intact), thr)
        near = full >= full.max() * (1 - 1e-3)
        assert np.array_equal(ratio[near], full[near])
        assert _first_of_largest(ratio) == _first_of_largest(full)
    # (14 of the 20: a surface bond's measure is its one triangle's, whose bound is
    # wider than a patch mean's; 15 before)
    assert scr.screened >= 12 and TIE < 1e-3


def test_a_criterion_that_redefines_its_value_is_not_screened(monkeypatch):
    """A subclass of a screened criterion with a value of its own keeps no Lipschitz
    constant made for its parent's value."""
    monkeypatch.setattr(screen_mod, "MIN_BONDS", 0)
    model = dv.DV(plate(0.1), E=E, nu=NU)
    sp_ = split(model)

    class Squared(Stress):
        def __call__(self, x, w, g, intact=None, bonds=None):
            return super().__call__(x, w, g, intact, bonds) ** 2

    plain, own = Stress(model, sp_), Squared(model, sp_)
    plain.prepare(model, FT, None, {})
    own.prepare(model, FT, None, {})
    assert plain.screen is not None and own.screen is None


def test_past_refresh_the_screen_stops_and_the_events_stay(monkeypatch, screens):
    """Once the bonds next to damage alone pass REFRESH, every bond, every event."""
    monkeypatch.setattr(screen_mod, "REFRESH", 0.03)
    mesh, sup = notched()
    model = dv.DV(mesh, E=E, nu=NU)
    kw = dict(ft=FT, gf=5e-4, teeth=3, max_events=60, stop_load_ratio=0.0)
    fast = dv.fracture(model, sup, None, **kw)
    (scr,) = screens
    assert scr.off and scr.ref is None
    unscreened(monkeypatch, Stress)
    same_events(fast, dv.fracture(model, sup, None, **kw))


def test_column_buffers_that_double_give_the_same_events(monkeypatch):
    """Where the system will not map ``max_rank`` columns at once, the buffers grow."""
    from dvstatic.crack import updates

    mesh, sup = notched(0.06)
    model = dv.DV(mesh, E=E, nu=NU)
    kw = dict(ft=FT, gf=5e-4, max_events=80, stop_load_ratio=0.0)
    lazy = dv.fracture(model, sup, None, **kw)

    def refuse(rows, cols):
        raise MemoryError("no")

    monkeypatch.setattr(updates, "_lazy_rows", refuse)
    same_events(lazy, dv.fracture(model, sup, None, **kw))


def test_apply_columns_sums_duplicate_entries():
    A = sp.csr_matrix(np.diag(np.arange(1.0, 7.0)))
    engine = DirectSolver(A, order=np.arange(6)[::-1].copy())
    u = sp.coo_matrix(
        (np.array([1.0, 2.0, 3.0]), (np.array([2, 2, 4]), np.array([0, 0, 1]))), (6, 2)
    )
    np.testing.assert_allclose(engine.apply_columns(u), engine.apply(u.toarray()).T)
