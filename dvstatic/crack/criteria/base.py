"""The breaking-criterion protocol and its registry.

A criterion says what every intact bond compares with its threshold, how its thresholds
follow from the material's strengths, and what a cracked bond softens by. A state is
``x_held + lambda x_grow``; the event loop (:mod:`dvstatic.crack.sla`) only calls
:meth:`Criterion.prepare` once and :meth:`Criterion.critical` at every event, which
finds the bond that fails at the smallest load factor ``lambda >= 0``. A criterion
linear in the state (``stress``, ``tension``) only defines :meth:`Criterion.__call__`;
one that is not (``mohr-coulomb``) overrides :meth:`Criterion.factors`. A new
criterion is a module in this package with a :func:`register`-ed subclass (and a test);
its name is then accepted by ``dv.fracture(criterion=...)`` and the scene.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from functools import cached_property
from typing import ClassVar, NamedTuple

import numpy as np

from ..strength import bond_strength, principal_response, weibull_factors
from . import screen
from .ratios import linear_factors
from .responses import per_bond, responses
from .screen import Screen

__all__ = ["Criterion", "Critical", "REGISTRY", "register", "criterion_for", "MODES"]

#: bonds whose ratios lie within this fraction of the largest tie: the first of them (by
#: index) is critical, so round-off (an update against a refactorisation, another BLAS)
#: does not decide which of equally loaded bonds breaks
TIE = 1e-9

#: lattices with at least this many bonds take the softening of a few bonds from their
#: rows, smaller ones from the whole product (Petersson's beam at 5,019 nodes, 14,592
#: bonds: 331 events/s with row slices, 380 without; medians of paired runs)
ROW_SLICE = 20_000

#: failure modes of a bond, by the code :meth:`Criterion.factors` gives: tension (the
#: normal stress across the face), shear (the Coulomb line, the face not in compression),
#: crushing (the Coulomb line, the face in compression) and out-of-plane (the Coulomb
#: line on a plane through the face's trace inclined out of the plane: the pair of the
#: face's normal stress and the out-of-plane principal stress, as a continuum
#: Mohr-Coulomb law sees it in plane stress and plane strain)
MODES = ("tension", "shear", "crushing", "out-of-plane")

#: criterion name -> class, in the order they were registered
REGISTRY: dict[str, type[Criterion]] = {}


def register(cls: type[Criterion]) -> type[Criterion]:
    """Class decorator: make ``cls`` available under ``cls.name``."""
    REGISTRY[cls.name] = cls
    return cls


def criterion_for(name: str, model, sp_) -> Criterion:
    """The registered criterion ``name`` for ``model`` and its split stiffness."""
    return REGISTRY[name](model, sp_)


class Critical(NamedTuple):
    """The next event: which bond, at which load factor, how, and its elongation there."""

    bond: int
    factor: float  #: the load factor (inf: no bond is loaded towards its threshold)
    mode: int  #: index into :data:`MODES`
    elongation: float  #: the bond's elongation in the critical state (length)


def _first_of_largest(values: np.ndarray) -> int:
    """The first index whose value ties with the largest (within :data:`TIE`)."""
    top = float(values.max())
    return int(np.flatnonzero(values >= top * (1.0 - TIE))[0]) if top > 0 else 0


class Criterion(ABC):
    """Base of the breaking criteria (abstract: a criterion defines :meth:`thresholds`
    and :meth:`__call__`).

    Parameters
    ----------
    model : DV or RV
    sp_ : SplitStiffness
        The per-triangle parts of the stiffness (:func:`dvstatic.lattice.damage.split`).
    """

    #: the name ``dv.fracture(criterion=...)`` takes
    name: ClassVar[str] = ""
    #: the strength keywords of ``dv.fracture`` beyond ``ft`` (and ``gf``) it needs
    parameters: ClassVar[tuple[str, ...]] = ()
    #: whether it fails faces in shear or crushing (then ``gf_shear`` applies)
    shear: ClassVar[bool] = False

    def __init__(self, model, sp_):
        self.sp = sp_
        geo = model.geometry
        self.length = geo.tri_l
        self.area = geo.tri_area * model.t
        self.n = geo.direction
        self.bonds = model.mesh.topology.bonds
        self.n_points = model.mesh.n_points
        self.h = None  # (n_bonds, 3): tension per unit xx, yy and xy stress
        #: the undamaged system :meth:`prepare` factorised (the event loop takes it over)
        self.factorised = None
        #: which bonds an event evaluates (:mod:`.screen`; None: all of them)
        self.screen: Screen | None = None

    # ------------------------------------------------------------------ to override
    def set_response(self, h: np.ndarray, patches) -> None:
        """Keep the bonds' tensions ``h`` (n_bonds, 3) and patch stresses (3 x (stress,
        covered)) under the unit uniform stresses xx, yy, xy."""
        self.h = h

    @abstractmethod
    def thresholds(self, s_tension, ftb, factors) -> np.ndarray:
        """First-crack threshold of every bond in the criterion's units, from the
        tension-based strengths ``s_tension`` (force), the tensile strength per bond
        ``ftb`` and the random-field ``factors`` (None: uniform)."""

    @abstractmethod
    def __call__(self, x, w, g, intact=None, bonds=None) -> np.ndarray:
        """What every intact bond compares with its threshold, shape (n_bonds,), in the
        state ``x`` (per unit load factor) of the damaged stiffness ``w, g``; of
        ``bonds`` (int array) only, if given."""

    def lipschitz(self) -> np.ndarray | None:
        """For a criterion linear in the state: per bond (n_bonds,), a bound on how far
        its value moves per unit of the largest elongation change over the triangles at
        its end nodes while they are undamaged; then an event evaluates only the bonds
        that can be critical (:mod:`.screen`). None (the default): every bond, every
        event."""
        return None

    def never_fails(self, first: bool) -> str:
        """The stop message where no bond reaches its threshold at any load factor
        (``first``: before any event, so the loading can never fail the lattice)."""
        what = (
            "the loading can never fail this lattice: no bond reaches its strength at any "
            "load factor"
            if first
            else "no unbroken bond is loaded towards its strength"
        )
        return (
            f"{what} (criterion {self.name!r} fails faces in tension only; compression "
            "fails by criterion='mohr-coulomb')"
        )

    def set_parameters(self, model, ftb, factors, **params) -> None:
        """Take the criterion's own strengths (:attr:`parameters`, checked by the
        criterion) per bond; ``ftb`` the tensile strength per bond, ``factors`` the
        random field (None: uniform). The base criterion takes none."""
        return None

    def factors(self, xh, xg, w, g, intact, threshold):
        """``(ratio, excess, mode)`` of every bond as if it were intact (n_bonds,) each:
        it reaches its threshold under ``xh + lambda xg`` at ``lambda = 1 / ratio``
        (ratio 0: never), the held part ``xh`` (None: none) alone overloads it by
        ``excess`` >= 1 (else 0), failing in ``mode`` (index into :data:`MODES`). This
        default serves criteria linear in the state, in tension."""
        vg = self(xg, w, g, intact)
        vh = 0.0 if xh is None else self(xh, w, g, intact)
        ratio, excess = linear_factors(vh, vg, threshold)
        return ratio, excess, np.zeros(len(vg), dtype=np.int64)

    # ------------------------------------------------------------------ shared
    def prepare(self, model, ft, weibull, timings: dict, dofs=None, params=None):
        """Thresholds (n_bonds,) in the criterion's units and the tension-based
        strengths (n_bonds,; force, for the fracture energies), from ``ft`` (a number
        or ``{region: ft}``), the criterion's own ``params`` (:attr:`parameters`) and the
        random field; ``dofs``: the problem's prescribed dofs (the uniform-stress
        responses hold them)."""
        t0 = time.perf_counter()
        mesh = model.mesh
        tens, patches, self.factorised = responses(model, self.length, self.area, dofs, self.sp)
        self.set_response(np.stack(tens, axis=1), patches)
        factors = None
        if weibull is not None:
            factors = weibull_factors(mesh.points[mesh.topology.bonds].mean(axis=1), weibull)
        ftb = per_bond(model, ft, "ft")
        s_t = bond_strength(principal_response(tens), ftb, factors)
        s = self.thresholds(s_t, ftb, factors)
        self.s_tension = s_t
        self.set_parameters(model, ftb, factors, **(params or {}))
        self.screen = None
        if self._screenable() and mesh.n_bonds >= screen.MIN_BONDS:
            lip = self.lipschitz()
            self.screen = None if lip is None else Screen(self.sp, mesh.points, lip, TIE)
        timings["strength"] = time.perf_counter() - t0
        return s, s_t

    def _screenable(self) -> bool:
        """Whether the screen may serve this criterion: linear (the base's
        :meth:`factors`) and its value and Lipschitz constant defined by the same class
        (a subclass that redefines the value keeps no constant made for another)."""

        def owner(name):
            return next(c for c in type(self).__mro__ if name in c.__dict__)

        return type(self).factors is Criterion.factors and owner("__call__") is owner("lipschitz")

    def softening(self, x, bonds=None) -> np.ndarray:
        """What a cracked bond softens by: its elongation (length) per unit load factor,
        shape (n_bonds,); of ``bonds`` (int array) only, if given."""
        x = np.asarray(x).ravel()
        if bonds is None or len(self.bonds) < ROW_SLICE:  # (a row slice costs more than
            out = self._elongation @ x  # the whole product on a small lattice)
            return out if bonds is None else out[bonds]
        return self._elongation[bonds] @ x

    @cached_property
    def _elongation(self):
        """(n_bonds, 2N) CSR: the bonds' elongations of a displacement."""
        import scipy.sparse as sp

        e = len(self.bonds)
        dofs = 2 * self.bonds[:, [0, 0, 1, 1]] + np.array([0, 1, 0, 1])
        vals = np.c_[-self.n, self.n]
        n_dof = 2 * self.n_points
        return sp.csr_matrix(
            (vals.ravel(), (np.repeat(np.arange(e), 4), dofs.ravel())), shape=(e, n_dof)
        )

    def cracked(self, x, modes, sense, elongation=None, bonds=None) -> np.ndarray:
        """The softening measure of every cracked bond in state ``x``, linear in ``x``,
        shape (n_bonds,), or of ``bonds`` only (``modes``, ``sense`` and ``elongation``
        then theirs): its elongation (``elongation``, if computed already) times its
        ``sense`` (``modes``, the modes the bonds first failed in, are for criteria that
        soften faces in shear)."""
        return sense * (self.softening(x, bonds) if elongation is None else elongation)

    def crack_measure(self, e: int, mode: int, x, d=None) -> tuple[float, float, float | None]:
        """``(peak, sense, spring)`` of bond ``e`` cracking in ``mode`` in state ``x``
        (``d`` the bonds' stiffness factors before it cracks):
        its softening measure there, the measure's sign from here on and the stiffness
        that makes ``spring peak^2 / 2`` the elastic energy at the crack (None: the
        bond's spring; the measure is its elongation)."""
        return float(self.softening(x)[e]), 1.0, None

    def critical(
        self, xh, xg, w, g, intact, d: np.ndarray, threshold: np.ndarray, sense=1.0, modes=0
    ) -> Critical:
        """The bond that reaches its threshold at the smallest load factor under
        ``xh + lambda xg`` (``xh`` the held part, None without one). Intact bonds
        (``d >= 1``) answer by the criterion, cracked ones by their elongation times
        their ``sense`` (:meth:`cracked`) against the tooth's threshold, in the mode of
        their first failure (``modes``, n_bonds,); bonds the
        held part alone overloads come first, at ``lambda = 0``, the most overloaded one
        first; of bonds that tie (within :data:`TIE`) the first by index."""
        c = np.flatnonzero(d < 1.0)  # cracked: by their softening measure
        rc = ec = np.zeros(0)
        if len(c):
            mc, sc = np.broadcast_to(modes, d.shape)[c], np.broadcast_to(sense, d.shape)[c]
            ch = 0.0 if xh is None else self.cracked(xh, mc, sc, bonds=c)
            rc, ec = linear_factors(ch, self.cracked(xg, mc, sc, bonds=c), threshold[c])
        if self.screen is None:
            ratio, excess, mode = self.factors(xh, xg, w, g, intact, threshold)
        else:
            floor = float(np.max(rc, where=d[c] > 0, initial=0.0))
            args = (self, xh, xg, w, g, intact, threshold, d >= 1.0, floor)
            ratio, excess = self.screen.factors(*args)
            mode = np.zeros(len(ratio), dtype=np.int64)
        ratio[c], excess[c] = rc, ec
        mode[c] = np.broadcast_to(modes, d.shape)[c]
        gone = d <= 0
        ratio[gone] = excess[gone] = 0.0
        if np.any(excess >= 1.0):
            e = _first_of_largest(excess)
            lam = 0.0
        else:
            e = _first_of_largest(ratio)
            lam = 1.0 / ratio[e] if ratio[e] > 0 else np.inf
        el = float(self.softening(xg, [e])[0]) * (lam if np.isfinite(lam) else 0.0)
        if xh is not None:
            el += float(self.softening(xh, [e])[0])
        return Critical(e, lam, int(mode[e]), el)
