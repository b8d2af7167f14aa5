"""Which bonds an event has to evaluate: a bound on how far each bond moved.

Finding the next event means the largest load ratio over every bond, but between two
events the state changes little away from the damage. The screen keeps a reference: the
criterion's values of every bond in an earlier state ``(xh0, xg0)``. A bond whose
patch (the triangles at its end nodes) is undamaged now and was then has a value linear
in the state with a fixed operator, so it moved by at most its Lipschitz constant
(:meth:`Criterion.lipschitz`) times the largest elongation change over its patch,
``|v_e(x) - v_e(x0)| <= L_e max_T |B_T (x - x0)|_inf``, which is bounded in turn by the
largest change over the blocks of :data:`BLOCK` triangles (consecutive along a Morton
curve) that the patches of its block of :data:`BLOCK` bonds meet (without held loads,
the candidates so found are then bounded by their own patches). That gives an upper
bound of every bond's ratio; only the bonds whose bound reaches the largest ratio found
exactly (ties included, :data:`TIE`) are evaluated, with the bonds next to damage (whose
measure changes with it) and those the held part could overload. The result is exact:
every bond that could be critical or tie with it is evaluated, with the same sums as the
whole lattice's (:meth:`~dvstatic.lattice.damage.TriangleSplit.local_measures`).

Where more than :data:`REFRESH` of the bonds would need evaluating (the first event;
the state moved far from the reference), every bond is evaluated and that state becomes
the reference; once the bonds next to damage alone pass it, every bond is evaluated at
every event (damage only grows). The bounds rest on one invariant of the event loop: an
intact bond's threshold does not change (``Bonds.advance`` changes it only as it cracks
the bond, and a cracked bond's patch is damaged).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ...lattice.damage import csr_rows
from ...mesh.ordering import spatial_order
from .ratios import linear_factors

__all__ = ["Screen", "REFRESH", "SLACK", "BLOCK", "MIN_BONDS"]

#: lattices with fewer bonds evaluate every bond at every event (below about this size
#: the screen's own work costs more than it saves: Petersson's beam at 9,780 nodes,
#: 28,669 bonds, 178 -> 200 events/s with it; a 2 x 1 plate with held loads and closing
#: cracks at 700 nodes 8.4 -> 10.8 s)
MIN_BONDS = 20_000

#: evaluate every bond (and take the state as the new reference) where the screen would
#: leave more than this fraction of them to evaluate (0.1 / 0.05 / 0.02 on Petersson's
#: beam at 9,780 nodes: 164 / 201 / 177 events/s; at 96,471 nodes 21.0 / 21.6 / 21.3)
REFRESH = 0.05
#: relative margin on the bounds (their own round-off)
SLACK = 1e-9
#: triangles (and bonds) per block of the bound
BLOCK = 64


class _Reference(NamedTuple):
    """The state every bond was last evaluated in, and what the bounds need of it."""

    xh: np.ndarray | None  #: (2N,) held part
    xg: np.ndarray  #: (2N,) growing part
    vh: np.ndarray | None  #: (n_bonds,) values of the held part
    vg: np.ndarray  #: (n_bonds,) values of the growing part
    #: bonds evaluated at every event: next to damage then (and, without held loads,
    #: those with no strength left; with held loads their bound says so)
    must: np.ndarray
    r_b: np.ndarray | None  #: per bond block, the largest ratio (without held loads)
    l_b: np.ndarray | None  #: per bond block, the largest Lipschitz constant per threshold


class Screen:
    """The bonds one event evaluates (module docstring).

    Parameters
    ----------
    sp_ : TriangleSplit
        The undamaged split stiffness the criterion works on.
    points : ndarray, shape (N, 2)
        The nodes (for the blocks).
    lipschitz : ndarray, shape (n_bonds,)
        Per bond, the bound on its value's change per unit of the largest elongation
        change over its patch (while the patch is undamaged).
    tie : float
        Relative width of a tie of the largest ratio (:data:`.base.TIE`).
    """

    def __init__(self, sp_, points: np.ndarray, lipschitz: np.ndarray, tie: float):
        self.sp, self.lip, self.tie = sp_, np.asarray(lipschitz, dtype=float), tie
        self._blocks(points)
        ends = sp_.ends
        self._node_bonds = _csr(ends.ravel(), np.repeat(np.arange(len(ends)), 2), sp_.n_nodes)
        self.ref: _Reference | None = None
        self.off = False  # the damage passed REFRESH: every bond at every event
        self.full = 0  # evaluations of every bond
        self.screened = 0  # events that evaluated a part of them
        self.evaluated = 0  # bonds evaluated in the screened events

    def _blocks(self, points: np.ndarray) -> None:
        """Triangles and bonds in blocks of :data:`BLOCK` along a Morton curve, and for
        every bond block the triangle blocks its bonds' patches meet (CSR)."""
        sp_ = self.sp
        tri_nodes = sp_.tri_nodes.reshape(-1, 3)
        m = len(tri_nodes)
        self._tri_order = spatial_order(points[tri_nodes].mean(axis=1))
        tri_block = np.empty(m, dtype=np.int64)
        tri_block[self._tri_order] = np.arange(m) // BLOCK
        self.n_tri_blocks = -(-m // BLOCK)
        e = len(sp_.ends)
        self.n_bond_blocks = -(-e // BLOCK)
        self._bond_order = spatial_order(points[sp_.ends].mean(axis=1))
        bond_block = np.empty(e, dtype=np.int64)
        bond_block[self._bond_order] = np.arange(e) // BLOCK
        self.bond_block = bond_block
        node_tris = _csr(tri_nodes.ravel(), np.repeat(tri_block, 3), sp_.n_nodes)
        # (bond block, node) pairs, then each node's triangle blocks
        n = sp_.n_nodes
        pairs = np.unique(np.repeat(bond_block, 2) * n + sp_.ends.ravel())
        blocks, starts = csr_rows(*node_tris, pairs % n)
        counts = np.diff(np.r_[starts, len(blocks)])
        nb = self.n_tri_blocks
        both = np.unique(np.repeat(pairs // n, counts) * nb + blocks)
        self._block_tris = _csr(both // nb, both % nb, self.n_bond_blocks)

    def factors(self, criterion, xh, xg, w, g, intact, threshold, intact_bonds, floor: float):
        """``(ratio, excess)`` (n_bonds,) of a criterion linear in the state, exact at
        every intact bond (``intact_bonds``, bool (n_bonds,); the others answer by their
        own measure) that can be critical or tie with it (0 elsewhere); ``floor`` the
        largest ratio known from elsewhere (the cracked bonds). The thresholds of bonds
        whose patch is undamaged are those of the reference (an intact bond's does not
        change)."""
        n = len(threshold)
        if self.off:  # damage only grows: past REFRESH, every bond from here on
            return self._all(criterion, xh, xg, w, g, intact, threshold)
        dirty = self._dirty(g, intact)
        if len(dirty) > REFRESH * n:
            self.off, self.ref = True, None
            return self._all(criterion, xh, xg, w, g, intact, threshold)
        ref = self.ref
        if ref is None or (xh is None) != (ref.xh is None):
            return self._everything(criterion, xh, xg, w, g, intact, threshold, dirty)
        args = (criterion, xh, xg, w, g, intact, threshold)
        first = np.union1d(ref.must, dirty)
        if xh is None:  # bounds by blocks of bonds
            tri = self.sp.triangle_change(xg - ref.xg)
            upper = ref.r_b + ref.l_b * self._block_change(tri)
            first = np.union1d(first, self._block_bonds(np.argmax(upper)))
        else:  # bond by bond (inf: the held part may leave no room)
            upper = self._upper(xh, xg, threshold)
            first = np.union1d(first, np.flatnonzero(upper == np.inf))
            first = np.union1d(first, [int(np.argmax(np.where(upper < np.inf, upper, -1.0)))])
        rf, ef = self._exact(*args, first)
        best = max(floor, float(np.max(rf, where=intact_bonds[first], initial=0.0)))

        def reaching(bound):  # the bounds that reach the largest ratio (ties included)
            return bound * (1.0 + SLACK) >= best * (1.0 - self.tie)

        if xh is None:  # the bonds of those blocks, by their own patches' bounds
            more = np.setdiff1d(self._block_bonds(np.flatnonzero(reaching(upper))), first)
            change = self.sp.patch_max(tri, more)
            own = (np.maximum(ref.vg[more], 0.0) + self.lip[more] * change) / threshold[more]
            second = more[reaching(own)]
        else:
            second = np.setdiff1d(np.flatnonzero(reaching(upper)), first)
        if best <= 0 or len(first) + len(second) > REFRESH * n:
            return self._everything(criterion, xh, xg, w, g, intact, threshold, dirty)
        rs, es = self._exact(*args, second)
        ratio, excess = np.zeros(n), np.zeros(n)
        ratio[first], excess[first] = rf, ef
        ratio[second], excess[second] = rs, es
        self.screened += 1
        self.evaluated += len(first) + len(second)
        return ratio, excess

    def _upper(self, xh, xg, threshold) -> np.ndarray:
        """Upper bounds of every bond's ratio (n_bonds,) under held loads; inf where
        the held part's bound leaves no room below the threshold."""
        ref, sp_, block = self.ref, self.sp, self.bond_block
        vg = ref.vg + self.lip * self._block_change(sp_.triangle_change(xg - ref.xg))[block]
        dh = self._block_change(sp_.triangle_change(xh - ref.xh))[block]
        room = threshold - (ref.vh + self.lip * dh)
        upper = np.full(len(room), np.inf)
        ok = room > SLACK * np.abs(threshold)  # (round-off within the bound's own)
        upper[ok] = np.maximum(vg[ok], 0.0) / room[ok]
        return upper

    def _block_change(self, tri: np.ndarray) -> np.ndarray:
        """Per block of bonds, a bound of every bond's largest elongation change over
        its patch, from every triangle's (M,; :meth:`TriangleSplit.triangle_change`):
        the largest over the triangle blocks the block's patches meet."""
        t = tri[self._tri_order]
        t = np.r_[t, np.zeros(-len(t) % BLOCK)].reshape(-1, BLOCK).max(axis=1)
        indptr, indices = self._block_tris  # (no row is empty: every bond has a triangle)
        return np.maximum.reduceat(t[indices], indptr[:-1])

    def _block_bonds(self, blocks) -> np.ndarray:
        """The bonds of bond blocks ``blocks`` (int or int array)."""
        idx = (np.atleast_1d(blocks)[:, None] * BLOCK + np.arange(BLOCK)).ravel()
        return self._bond_order[idx[idx < len(self._bond_order)]]

    def _by_block(self, values: np.ndarray, fill: float) -> np.ndarray:
        """The largest of ``values`` (n_bonds,) in every bond block."""
        v = np.full(self.n_bond_blocks * BLOCK, fill)
        v[: len(values)] = values[self._bond_order]
        return v.reshape(-1, BLOCK).max(axis=1)

    def _exact(self, criterion, xh, xg, w, g, intact, threshold, bonds):
        if not len(bonds):
            return np.zeros(0), np.zeros(0)
        vg = criterion(xg, w, g, intact, bonds)
        vh = 0.0 if xh is None else criterion(xh, w, g, intact, bonds)
        return linear_factors(vh, vg, threshold[bonds])

    def _all(self, criterion, xh, xg, w, g, intact, threshold):
        """Every bond, no reference kept."""
        self.full += 1
        vh = 0.0 if xh is None else criterion(xh, w, g, intact)
        return linear_factors(vh, criterion(xg, w, g, intact), threshold)

    def _everything(self, criterion, xh, xg, w, g, intact, threshold, dirty):
        """Every bond, and this state as the reference."""
        vg = criterion(xg, w, g, intact)
        vh = None if xh is None else criterion(xh, w, g, intact)
        must, r_b, l_b = dirty, None, None
        if xh is None:  # per block: the largest ratio and Lipschitz constant per ratio
            ok = threshold > 0
            ok[dirty] = False
            must = np.flatnonzero(~ok)
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio0 = np.where(ok, np.maximum(vg, 0.0) / threshold, -np.inf)
                r_b = self._by_block(ratio0, -np.inf)
                l_b = self._by_block(np.where(ok, self.lip / threshold, 0.0), 0.0)
        xh = None if xh is None else xh.copy()
        self.ref = _Reference(xh, xg.copy(), vh, vg, must, r_b, l_b)
        self.full += 1
        return linear_factors(0.0 if vh is None else vh, vg, threshold)

    def _dirty(self, g, intact) -> np.ndarray:
        """The bonds (sorted indices) whose patch has a damaged triangle (one whose
        bonds are not all intact, or whose coupling differs from the undamaged one;
        the springs of a triangle with intact bonds are the undamaged ones)."""
        sp_ = self.sp
        tri = np.flatnonzero((intact < 1.0) | (g != sp_.g))
        if not len(tri):
            return tri
        nodes = np.unique(sp_.tri_nodes.reshape(-1, 3)[tri])
        return np.unique(csr_rows(*self._node_bonds, nodes)[0])


def _csr(rows: np.ndarray, cols: np.ndarray, n_rows: int):
    """``(indptr, indices)`` of the pattern with entries ``(rows, cols)`` (rows sorted
    stably; duplicates kept)."""
    order = np.argsort(rows, kind="stable")
    indptr = np.zeros(n_rows + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=n_rows), out=indptr[1:])
    return indptr, cols[order]
