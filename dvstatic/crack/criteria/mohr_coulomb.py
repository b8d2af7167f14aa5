"""``criterion="mohr-coulomb"``: Coulomb's shear line with a tension cut-off on each
bond's Voronoi face."""

from __future__ import annotations

import math

import numpy as np

from ...errors import InputError
from ...stress.virial import continuum_stress, strain_operator
from .base import MODES, register
from .ratios import linear_factors
from .responses import per_bond
from .stress import Stress

__all__ = ["MohrCoulomb", "MAX_FRICTION_ANGLE", "OUT_OF_PLANE", "ucs"]

#: the code of the out-of-plane mode in :data:`~.base.MODES`
OUT_OF_PLANE = MODES.index("out-of-plane")

#: friction angles (degrees) accepted: [0, MAX_FRICTION_ANGLE)
MAX_FRICTION_ANGLE = 70.0


def ucs(cohesion: float, friction_angle: float) -> float:
    """The continuum's uniaxial compressive strength ``2 c cos(phi) / (1 - sin(phi))``
    (stress units; ``friction_angle`` in degrees)."""
    phi = math.radians(friction_angle)
    return 2.0 * cohesion * math.cos(phi) / (1.0 - math.sin(phi))


def _face_average(model):
    """(n_bonds, n_triangles): the area-weighted mean over every bond's triangles."""
    import scipy.sparse as sp

    mesh = model.mesh
    tb = mesh.topology.tri_bonds
    area = np.repeat(model.geometry.tri_area, 3)
    rows, cols = tb.ravel(), np.repeat(np.arange(mesh.n_triangles), 3)
    a = sp.csr_matrix((area, (rows, cols)), shape=(mesh.n_bonds, mesh.n_triangles))
    return sp.diags(1.0 / np.asarray(a.sum(axis=1)).ravel()) @ a


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
    *tension*), ``|tau| + sigma_n tan(phi) = c`` (Coulomb's line: mode *shear* if the
    face is not in compression there, *crushing* if it is), or Coulomb's line is reached
    on a plane through the face's trace tilted out of the plane (mode *out-of-plane*).

    The out-of-plane test is the continuum's: a plane body has a third principal
    stress, ``sigma_zz = 0`` in plane stress and ``nu (sigma_xx + sigma_yy)`` in plane
    strain, and a 3-D Mohr-Coulomb law (as FE codes evaluate it at every point of a
    plane model) takes the largest and smallest of all three. The planes whose normal
    lies between the face's normal ``n`` and ``z`` carry the pair ``(sigma_n,
    sigma_zz)`` with no shear between them, and reach Coulomb's line when
    ``k+ max(sigma_n, sigma_zz) - k- min(sigma_n, sigma_zz) = c``, ``k+- = (1 +- sin
    phi) / (2 cos phi)``. Over the faces' directions ``sigma_n`` spans the in-plane
    principal stresses, so the lattice's faces together reproduce the full 3-D
    envelope: under biaxial compression in plane stress it fails at the uniaxial
    strength, on the faces normal to the larger compression, where the in-plane faces
    alone would strengthen with the lateral stress like confinement and never fail at
    equal compression. Failing out of plane the face loses its bond (the wedge above the
    tilted plane slides out of the plane, so the face no longer carries normal stress),
    softening with ``gf_shear`` along the same measure of its trial stress.

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
    shear = True

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
        phi = np.radians(per_bond(model, friction_angle, "friction_angle", _angle))
        self.tan = np.tan(phi)
        #: the out-of-plane test's factors k+ and k- (n_bonds,)
        self.k_plus = (1.0 + np.sin(phi)) / (2.0 * np.cos(phi))
        self.k_minus = (1.0 - np.sin(phi)) / (2.0 * np.cos(phi))
        self.model = model
        self._faces = _face_average(model)
        self._strain = strain_operator(model.mesh)
        ratio = np.array([m.out_of_plane for m in model.all_materials])
        #: sigma_zz / (sigma_xx + sigma_yy) per bond (0 in plane stress)
        self.zz = self._faces @ ratio[model.material_of_triangle]

    # ------------------------------------------------------- faces failed in shear
    def trial(self, x):
        """The face's own elastic trial stress: the continuum law of each triangle
        applied to its P1 strain, averaged (by area) over the bond's triangles. Returns
        the normal and shear stress on every bond's face, the out-of-plane stress and
        the energy density ``sigma : eps`` there, (n_bonds,) each."""
        eps = (self._strain @ np.asarray(x).ravel()).reshape(-1, 3)
        sig = continuum_stress(self.model, eps)
        sxx, syy, sxy = sig[:, 0, 0], sig[:, 1, 1], sig[:, 0, 1]
        density = sxx * eps[:, 0] + syy * eps[:, 1] + 2 * sxy * eps[:, 2]
        v = self._faces @ np.c_[sxx, syy, sxy, density]
        n = self.n
        nx2, ny2, nxy = n[:, 0] ** 2, n[:, 1] ** 2, n[:, 0] * n[:, 1]
        sn = v[:, 0] * nx2 + v[:, 1] * ny2 + 2 * v[:, 2] * nxy
        tau = v[:, 2] * (nx2 - ny2) + nxy * (v[:, 1] - v[:, 0])
        return sn, tau, self.zz * (v[:, 0] + v[:, 1]), v[:, 3]

    def cracked(self, x, modes, sense, elongation=None, bonds=None) -> np.ndarray:
        """Cracked in tension: the elongation times its sense. Failed in shear or
        crushing: Coulomb's measure ``s tau + sigma_n tan(phi)`` of the face's own trial
        stress (:meth:`trial`; ``s`` the sense of the shear as the face failed), which a
        softening face's strain makes grow as it softens; out of plane, the
        out-of-plane measure of the same trial stress (:meth:`out_of_plane`, ``s`` the
        order of the pair as it failed)."""
        out = super().cracked(x, modes, sense, elongation, bonds)
        modes = np.asarray(modes)
        shear = modes != 0
        if np.any(shear):
            sl = slice(None) if bonds is None else bonds
            sn, tau, szz, _ = (v[sl] for v in self.trial(x))
            sense = np.broadcast_to(sense, sn.shape)
            oop = self.out_of_plane(sn, szz, sense, bonds)
            coulomb = sense * tau + sn * self.tan[sl]
            out = np.where(shear, np.where(modes == OUT_OF_PLANE, oop, coulomb), out)
        return out

    def out_of_plane(self, sn, szz, sense, bonds=None) -> np.ndarray:
        """The out-of-plane Coulomb measure of the pair ``(sigma_n, sigma_zz)``, linear
        on either side of their order: ``sense`` +1 where ``sigma_zz >= sigma_n``
        (``k+ sigma_zz - k- sigma_n``), -1 where not (``k+ sigma_n - k- sigma_zz``);
        ``bonds``: the bonds the arrays are of (None: all)."""
        sl = slice(None) if bonds is None else bonds
        hi, lo = np.where(sense > 0, szz, sn), np.where(sense > 0, sn, szz)
        return self.k_plus[sl] * hi - self.k_minus[sl] * lo

    def crack_measure(self, e: int, mode: int, x, d=None):
        """Cracked in tension: the base's. In shear or crushing: the face's Coulomb
        measure of its trial stress, the sense of its shear, and the stiffness that
        makes ``spring peak^2 / 2`` the continuum's elastic energy in the bond's share
        of the body (``sigma : eps l_e r_e t / 4``; a crack band one face wide); out of
        plane, the out-of-plane measure and the order of its pair."""
        if mode == 0:
            return super().crack_measure(e, mode, x, d)
        sn, tau, szz, density = (v[e] for v in self.trial(x))
        if mode == OUT_OF_PLANE:
            sense = 1.0 if szz >= sn else -1.0
            peak = float(self.out_of_plane(sn, szz, sense, [e])[0])
        else:
            sense = 1.0 if tau >= 0 else -1.0
            peak = sense * tau + sn * self.tan[e]
        geo = self.model.geometry
        energy = 0.25 * density * geo.length[e] * geo.r[e] * self.model.t
        return float(peak), sense, (2.0 * energy / peak**2 if peak > 0 else 0.0)

    def face(self, x, w, g, intact=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Normal, shear and out-of-plane stress on every bond's face in state ``x``,
        (n_bonds,) each (stress units): the unbiased patch stress's traction on the
        face; next to damage the normal stress the bond's own tension stands for (as the
        ``stress`` criterion, slivers excepted); a bond without a patch takes the normal
        stress its tension stands for and no shear; ``sigma_zz`` from the patch stress
        (0 in plane stress)."""
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
        return sn, tau, self.zz * (v[:, 0] + v[:, 1])

    def never_fails(self, first: bool) -> str:
        what = (
            "the loading can never fail this lattice: no face reaches the Mohr-Coulomb "
            "envelope at any load factor"
            if first
            else "no unbroken face is loaded towards the Mohr-Coulomb envelope"
        )
        return (
            f"{what} (the stress stays inside it however large the load: compression "
            "confined on every side, plane strain's sigma_zz = nu (sigma_xx + sigma_yy) "
            "included, since Coulomb's line has no cap)"
        )

    def factors(self, xh, xg, w, g, intact, threshold):
        b, q, bz = self.face(xg, w, g, intact)
        a, p, az = (0.0, 0.0, 0.0) if xh is None else self.face(xh, w, g, intact)
        tan = self.tan
        tests = [linear_factors(a, b, self.ft)]  # the cut-off
        for sign in (1.0, -1.0):  # Coulomb's line, either sense of the shear
            tests.append(linear_factors(sign * p + a * tan, sign * q + b * tan, self.c))
        for sense in (1.0, -1.0):  # out of plane, either order of (sigma_n, sigma_zz)
            held = self.out_of_plane(a, az, sense)
            tests.append(linear_factors(held, self.out_of_plane(b, bz, sense), self.c))
        ratio = np.stack([r for r, _ in tests])
        excess = np.stack([x for _, x in tests])
        which = np.argmax(np.where(np.any(excess >= 1.0, axis=0), excess, ratio), axis=0)
        pick = np.arange(len(b))
        r, x = ratio[which, pick], excess[which, pick]
        lam = np.where(x >= 1.0, 0.0, np.divide(1.0, r, out=np.zeros_like(r), where=r > 0))
        compressed = a + lam * b < 0
        mode = np.where(which == 0, 0, np.where(compressed, 2, 1))
        mode[which >= 3] = OUT_OF_PLANE
        return r, x, mode
