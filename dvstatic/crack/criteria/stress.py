"""``criterion="stress"`` (the default): a Rankine criterion on each bond's Voronoi face."""

from __future__ import annotations

import numpy as np

from ..strength import principal_response
from .base import Criterion, register
from .responses import voigt

__all__ = ["Stress"]


@register
class Stress(Criterion):
    """The normal stress across the bond's face against ``ft``.

    Away from damage, ``H_nn sigma_nn``, the normal stress across the face times the
    bond's tension per unit normal stress ``H_nn``. ``sigma`` is the mean stress of the
    triangles at the bond's two end nodes (a surface bond's: its own triangle,
    :meth:`~dvstatic.lattice.damage.TriangleSplit.criterion_total`), corrected by the
    inverse of that patch's response to uniform stress (so that it is exact under any
    uniform stress). Next to
    damage (in a damaged triangle), the bond's own tension without the part that stress
    along its face causes, ``T_e - (H_e : sigma - H_nn sigma_nn)``: the tension resolves
    the stress concentration at a crack tip that a patch mean would smear, and damaged
    triangles are left out of ``sigma`` so that the crack does not shield the bonds
    ahead of it. Under uniform stress both are ``H_nn sigma_nn``. Slivers whose tension
    hardly follows the normal stress (``H_nn < lambda_max(H_e) / 4``) use their tension.
    """

    name = "stress"

    def set_response(self, h: np.ndarray, patches) -> None:
        """Tensions (n_bonds, 3) and patch stresses (3 x (stress, covered)) under the unit
        uniform stresses xx, yy, xy; ``h_nn = n . H_e . n``, a bond's tension per unit
        normal stress across its face."""
        self.h = h
        n = self.n
        self.h_nn = h[:, 0] * n[:, 0] ** 2 + h[:, 1] * n[:, 1] ** 2 + h[:, 2] * n[:, 0] * n[:, 1]
        lam = principal_response([h[:, 0], h[:, 1], h[:, 2]])
        p = np.stack([voigt(s) for s, _ in patches], axis=2)  # (xx, yy, xy) -> patch
        ok = np.linalg.cond(p) < 1e3
        self.unbias = np.broadcast_to(np.eye(3), p.shape).copy()
        self.unbias[ok] = np.linalg.inv(p[ok])
        #: slivers, and bonds whose patch is degenerate, use their tension
        self.use_tension = (self.h_nn < 0.25 * lam) | ~ok | ~patches[0][1]
        # the normal measure and H_e : sigma as rows acting on the raw patch stress
        # (the unbiasing folded in): two products per bond instead of a 3x3 one
        nv = np.stack([n[:, 0] ** 2, n[:, 1] ** 2, 2 * n[:, 0] * n[:, 1]], axis=1)
        self._a_normal = self.h_nn[:, None] * np.einsum("ei,eij->ej", nv, self.unbias)
        self._a_h = np.einsum("ei,eij->ej", h, self.unbias)

    def thresholds(self, s_tension, ftb, factors):
        scale = ftb * self.h_nn * (1.0 if factors is None else factors)
        return np.where(self.use_tension, s_tension, scale)

    def __call__(self, x, w, g, intact=None, bonds=None) -> np.ndarray:
        normal, _, covered, t = self._parts(x, w, g, intact, bonds)
        use_tension = self.use_tension if bonds is None else self.use_tension[bonds]
        return np.where(covered & ~use_tension, normal, t)

    def lipschitz(self) -> np.ndarray:
        """Per bond, how far its measure can move per unit of the largest elongation
        change over its patch (the triangles at its end nodes), while the patch is
        undamaged (n_bonds,): the normal measure ``a . s`` moves at most ``|a|_1`` times
        the patch mean of ``|V_T diag(l_T) Q_T|_inf``; a tension at most the patch sum
        of ``|Q_T|_inf``."""
        sp_ = self.sp
        total = sp_.criterion_total(self.area)
        covered = total > 0
        mean = sp_.criterion_total(sp_.q_norms(sp_.w, sp_.g, self.length)) / np.where(
            covered, total, 1.0
        )
        normal = np.abs(self._a_normal).sum(axis=1) * mean
        tension = sp_.patch_total(sp_.q_norms(sp_.w, sp_.g))
        return np.where(covered & ~self.use_tension, normal, tension)

    def measure(self, x, w, g, intact=None):
        """``(normal, v, covered, t)`` of state ``x``: the normal measure (n_bonds,;
        tension units, see the class), the unbiased patch stress ``v`` (n_bonds, 3; xx,
        yy, xy; 0 where the patch is empty), whether the patch has a triangle (bool,
        n_bonds) and the tensions."""
        normal, s, covered, t = self._parts(x, w, g, intact)
        v = np.einsum("eij,ej->ei", self.unbias, s)
        return normal, np.where(covered[:, None], v, 0.0), covered, t

    def _parts(self, x, w, g, intact=None, bonds=None):
        """``(normal, s, covered, t)``: :meth:`measure`'s with the raw patch stress ``s``
        (n_bonds, 3) in place of the unbiased one; of ``bonds`` (int array) only, if
        given (the same numbers)."""
        sl = slice(None) if bonds is None else bonds
        if bonds is None:
            f = self.sp.forces(x, w, g)
            t = self.sp.tension(x, w, g, f)
            s, covered = self.sp.patch_voigt(x, w, g, self.length, self.area, intact, f)
        else:
            t, s, covered = self.sp.local_measures(x, w, g, self.length, self.area, intact, bonds)
        normal = np.einsum("ej,ej->e", self._a_normal[sl], s)
        if intact is not None and not intact.all():
            along = np.einsum("ej,ej->e", self._a_h[sl], s) - normal
            normal = np.where(self._near_damage(intact)[sl], t - along, normal)
        return normal, s, covered, t

    def _near_damage(self, intact: np.ndarray) -> np.ndarray:
        """Bonds of a damaged triangle (the damaged bond's neighbours), (n_bonds,) bool."""
        hit = np.zeros(len(self.bonds), dtype=bool)
        hit[self.sp.tri_bonds[intact < 1].ravel()] = True
        return hit
