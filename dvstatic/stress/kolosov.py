"""Kolosov-Muskhelishvili fields: exact plane-elastic states to fit stresses with.

In a homogeneous isotropic body without body forces every plane displacement field
is given by two analytic functions::

    2 mu u = kappa phi(z) - z conj(phi'(z)) - conj(psi(z))
    sxx + syy = 4 Re phi'(z),     syy - sxx + 2 i sxy = 2 (conj(z) phi''(z) + psi'(z))

with ``kappa = (3 - nu*) / (1 + nu*)`` for the in-plane constants. Powers ``z^k`` of
``phi`` and ``psi`` give basis fields that are in equilibrium and compatible: a fit
by them averages the lattice's fluctuations without leaving the space of elastic
states. With negative powers (Laurent series about a hole's centre) the basis holds
the fields around a circular hole under uniform or pressure loading exactly (Kirsch,
Lame), so a fit at a hole does not blur its stress concentration.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Fields"]


class Fields:
    """Stresses (and displacements) of the K-M fields of degree up to ``p``.

    Powers ``1..p`` of ``phi`` and ``psi`` (``laurent``: ``-p..p``), each with a real
    and an imaginary coefficient; the fields without stress (rigid motions) are left
    out: ``4 p - 1`` fields (``8 p - 1`` with ``laurent``).

    Parameters
    ----------
    E, nu : float
        In-plane constants (plane strain: the effective ones).
    p : int
        Largest power, >= 1.
    laurent : bool
        Also the negative powers (about a centre outside the body).
    """

    def __init__(self, E: float, nu: float, p: int, laurent: bool = False):
        self.E, self.nu = float(E), float(nu)
        self.mu = E / (2 * (1 + nu))
        self.kappa = (3 - nu) / (1 + nu)
        lo = -p if laurent else 1
        phi = [("phi", k, c) for k in range(lo, p + 1) if k != 0 for c in (1.0, 1j)]
        self.terms = [t for t in phi if not (t[1] == 1 and t[2] == 1j)]  # a rotation
        self.terms += [("psi", k, c) for k in range(lo, p + 1) if k != 0 for c in (1.0, 1j)]

    @property
    def size(self) -> int:
        return len(self.terms)

    def stress(self, z: np.ndarray) -> np.ndarray:
        """``(sxx, syy, sxy)`` of every field at ``z`` (scaled coordinates: divide by
        the length scale for physical units), shape ``z.shape + (size, 3)``."""
        pw = _Powers(z)
        out = np.empty(z.shape + (self.size, 3))
        zc = np.conj(z)
        for col, (kind, k, c) in enumerate(self.terms):
            if kind == "phi":
                tr = 4 * np.real(c * k * pw(k - 1))
                dev = 2 * zc * (c * k * (k - 1) * pw(k - 2)) if k != 1 else 0.0 * z
            else:
                tr, dev = 0.0, 2 * c * k * pw(k - 1)
            out[..., col, 0] = 0.5 * (tr - dev.real)
            out[..., col, 1] = 0.5 * (tr + dev.real)
            out[..., col, 2] = 0.5 * dev.imag
        return out

    def displacement(self, z: np.ndarray) -> np.ndarray:
        """``2 mu u`` (complex ux + i uy) of every field at ``z`` (scaled coordinates:
        multiply by the length scale), shape ``z.shape + (size,)``."""
        pw = _Powers(z)
        out = np.empty(z.shape + (self.size,), dtype=complex)
        for col, (kind, k, c) in enumerate(self.terms):
            if kind == "phi":
                out[..., col] = self.kappa * c * pw(k) - z * np.conj(c * k * pw(k - 1))
            else:
                out[..., col] = -np.conj(c * pw(k))
        return out


class _Powers:
    """Integer powers of an array, each computed once."""

    def __init__(self, z: np.ndarray):
        self.z = z
        self.cache: dict[int, np.ndarray] = {0: np.ones_like(z)}

    def __call__(self, k: int) -> np.ndarray:
        if k not in self.cache:
            self.cache[k] = self.z**k if k > 0 else 1.0 / self.z ** (-k)
        return self.cache[k]
