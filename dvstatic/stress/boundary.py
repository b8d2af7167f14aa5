"""The boundary as the stress recovery sees it: smooth pieces, outward normals, the
stress vector read from the nodal forces, the centres of holes.

The stress vector on the boundary is read from the lattice's own nodal forces, not
from the load objects: at a boundary node the internal force ``(K u)_i`` is the whole
external force there (applied loads plus support reactions), so one ``Pressure``, one
``Traction`` per edge or the same forces as point loads give the same stress. Divided
by the node's share of the boundary length it is the traction; along each smooth piece
(the boundary cut at corners) it is smoothed by a local linear fit over the recovery's
averaging radius (support reactions of a lattice scatter from node to node; applied
tractions come through unchanged where they are linear), and the piece's end nodes
(corners) take the value the fit extrapolates to them, so that a corner has one
stress vector per piece.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mesh import Mesh

__all__ = ["Boundary", "CORNER_DEGREES", "HOLE_RADII"]

#: a boundary node whose edges turn by more than this is a corner (pieces end there)
CORNER_DEGREES = 20.0
#: a concave piece whose radius of curvature is under this many local spacings bends
#: around a hole: the fits there use the Laurent fields about its centre
HOLE_RADII = 100.0
#: half width of the arc (in local spacings) of the circle fitted for the curvature
CURVATURE_SPACINGS = 3.0


@dataclass(frozen=True, eq=False)
class Boundary:
    """Boundary edges and smooth pieces of a mesh (bounded meshes only).

    Attributes
    ----------
    edges : ndarray of int, shape (E, 2)
        Boundary edges, the body on their left.
    length : ndarray, shape (E,)
    normal, tangent : ndarray, shape (E, 2)
        Outward unit normal and unit tangent of every edge.
    midpoint : ndarray, shape (E, 2)
    slot_node, slot_edge_a, slot_edge_b : ndarray of int, shape (S,)
        One slot per (node, piece): the node and its edges before and after it in the
        piece (-1 at the end of an open piece). A corner node has two slots.
    slot_piece : ndarray of int, shape (S,)
    slot_s : ndarray, shape (S,)
        Arc length of the slot's node along its piece.
    slot_end : ndarray of bool, shape (S,)
        The slot is an end of an open piece (a corner).
    pieces : list of (ndarray, bool)
        The slots of every piece in order, and whether the piece is closed.
    piece_length : ndarray, shape (n_pieces,)
    """

    edges: np.ndarray
    length: np.ndarray
    normal: np.ndarray
    tangent: np.ndarray
    midpoint: np.ndarray
    slot_node: np.ndarray
    slot_edge_a: np.ndarray
    slot_edge_b: np.ndarray
    slot_piece: np.ndarray
    slot_s: np.ndarray
    slot_end: np.ndarray
    pieces: list
    piece_length: np.ndarray

    @classmethod
    def of(cls, mesh: Mesh) -> Boundary:
        """The boundary of ``mesh`` (its loops cut at corners into pieces)."""
        e = mesh.boundary_edges
        a, b = mesh.points[e[:, 0]], mesh.points[e[:, 1]]
        d = b - a
        length = np.hypot(d[:, 0], d[:, 1])
        tangent = d / length[:, None]
        normal = np.c_[tangent[:, 1], -tangent[:, 0]]
        slots: list[tuple[int, int, int, int, float, bool]] = []
        pieces, plength = [], []
        for loop in _loops(e, mesh.n_points):
            for edge_ids, closed in _cut(tangent, loop):
                first = len(slots)
                s = np.concatenate([[0.0], np.cumsum(length[edge_ids])])
                nodes = np.r_[e[edge_ids, 0], e[edge_ids[-1], 1]]
                m = len(edge_ids) if closed else len(edge_ids) + 1
                for k in range(m):
                    ea = edge_ids[k - 1] if (k > 0 or closed) else -1
                    eb = edge_ids[k] if k < len(edge_ids) else -1
                    end = not closed and (k == 0 or k == m - 1)
                    slots.append((int(nodes[k]), int(ea), int(eb), len(pieces), s[k], end))
                pieces.append((np.arange(first, len(slots)), closed))
                plength.append(s[-1])
        arr = np.array(slots, dtype=float).reshape(-1, 6)
        as_int = arr[:, :4].astype(np.int64)
        return cls(
            e,
            length,
            normal,
            tangent,
            0.5 * (a + b),
            as_int[:, 0],
            as_int[:, 1],
            as_int[:, 2],
            as_int[:, 3],
            arr[:, 4],
            arr[:, 5].astype(bool),
            pieces,
            np.array(plength),
        )

    @property
    def slot_length(self) -> np.ndarray:
        """The slot's share of its piece's length (half of each of its edges)."""
        out = np.zeros(len(self.slot_node))
        for edge in (self.slot_edge_a, self.slot_edge_b):
            ok = edge >= 0
            out[ok] += 0.5 * self.length[edge[ok]]
        return out

    @property
    def slot_normal(self) -> np.ndarray:
        """Outward normal at every slot: the mean of its edges' normals in the piece."""
        out = np.zeros((len(self.slot_node), 2))
        for edge in (self.slot_edge_a, self.slot_edge_b):
            ok = edge >= 0
            out[ok] += self.normal[edge[ok]]
        return out / np.hypot(out[:, 0], out[:, 1])[:, None]

    def node_length(self, n_points: int) -> np.ndarray:
        """Every node's share of the boundary length, shape (N,) (0 inside)."""
        return np.bincount(self.slot_node, self.slot_length, n_points)

    def tractions(
        self, fext: np.ndarray, thickness: float, radius: np.ndarray, fixed: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """The stress vector per slot and per edge from the external nodal forces.

        Parameters
        ----------
        fext : ndarray, shape (N, 2)
            External force on every node (applied loads and reactions, body forces
            taken out).
        thickness : float
        radius : ndarray, shape (N,)
            Smoothing radius of every node (length).
        fixed : ndarray of bool, shape (N, 2)
            Prescribed dofs: where they are, the force is (partly) a reaction.

        Returns
        -------
        slot_t : ndarray, shape (S, 2)
        edge_t : ndarray, shape (E, 2)
            The mean of its two end slots' (in its piece).

        A corner's force is shared by its pieces: a component prescribed on one piece
        (a support along it) and free on the other is that piece's reaction, less what
        the other piece's stress vector (extrapolated from its own nodes) carries there.
        """
        raw = fext[self.slot_node] / (thickness * self.slot_length[:, None])
        first = self._smooth(raw, radius, corners=False)
        raw = self._corner_shares(fext, thickness, first, fixed)
        slot_t = self._smooth(raw, radius, corners=True, fixed=fixed)
        edge_t = np.zeros((len(self.edges), 2))
        for edge in (self.slot_edge_a, self.slot_edge_b):
            ok = edge >= 0
            edge_t[edge[ok]] += 0.5 * slot_t[ok]
        return slot_t, edge_t

    def _smooth(self, raw, radius, corners: bool, fixed=None) -> np.ndarray:
        """Local linear fits along every piece; corner slots count where ``corners``
        and the component is supported on the slot's piece, else hardly at all (their
        force is shared with the other piece)."""
        out = np.zeros_like(raw)
        weight = np.where(self.slot_end, 1e-9, 1.0)[:, None] * np.ones(2)
        if corners:
            weight = np.where(self.slot_end[:, None] & self.supported(fixed), 1.0, weight)
        weight = weight * self.slot_length[:, None]
        for slots, closed in self.pieces:
            total = self.piece_length[self.slot_piece[slots[0]]] if closed else None
            for c in range(2):
                out[slots, c] = _smooth_along(
                    self.slot_s[slots],
                    raw[slots, c : c + 1],
                    weight[slots, c],
                    radius[self.slot_node[slots]],
                    total,
                )[:, 0]
        return out

    def supported(self, fixed: np.ndarray) -> np.ndarray:
        """(S, 2): the component is prescribed at the slot's node and at the next node
        along its piece (a support along the piece, not just at the corner)."""
        other = np.where(
            self.slot_edge_b >= 0,
            self.edges[np.maximum(self.slot_edge_b, 0), 1],
            self.edges[np.maximum(self.slot_edge_a, 0), 0],
        )
        return fixed[self.slot_node] & fixed[other]

    def _corner_shares(self, fext, thickness, first, fixed) -> np.ndarray:
        """Raw slot tractions with every corner's force shared between its pieces."""
        raw = fext[self.slot_node] / (thickness * self.slot_length[:, None])
        sup = self.supported(fixed)
        ends = np.flatnonzero(self.slot_end)
        for node in np.unique(self.slot_node[ends]):
            slots = ends[self.slot_node[ends] == node]
            length = self.slot_length[slots]
            for c in range(2):
                s_sup = sup[slots, c]
                if not s_sup.any():
                    continue
                rest = fext[node, c] / thickness - np.sum(first[slots[~s_sup], c] * length[~s_sup])
                raw[slots[s_sup], c] = rest / length[s_sup].sum()
        return raw

    def hole_centres(self, points: np.ndarray, h: np.ndarray) -> np.ndarray:
        """Centre (x, y) and radius of the circle through the piece around every slot
        where the piece bends around a hole (centre outside the body, radius under
        ``HOLE_RADII`` local spacings), NaN elsewhere; shape (S, 3)."""
        out = np.full((len(self.slot_node), 3), np.nan)
        for slots, closed in self.pieces:
            if len(slots) < 3:
                continue
            s = self.slot_s[slots]
            total = self.piece_length[self.slot_piece[slots[0]]] if closed else None
            p = points[self.slot_node[slots]]
            hh = h[self.slot_node[slots]]
            near = _arc_windows(s, CURVATURE_SPACINGS * hh, total)
            idx, valid = near
            # circle x^2 + y^2 = 2 a x + 2 b y + c fitted in coordinates centred on the
            # slot and scaled by its spacing (well conditioned at any position); on a
            # straight window (singular without it) the ridge term keeps the solve
            # regular, and its centre lies on the line, which the `toward` test rejects
            q = np.where(valid[..., None], (p[idx] - p[:, None, :]) / hh[:, None, None], 0.0)
            w = valid.astype(float)
            A = np.concatenate([2 * q, np.ones(q.shape[:-1] + (1,))], axis=-1) * w[..., None]
            rhs = (q**2).sum(-1) * w
            M = np.einsum("nki,nkj->nij", A, A)
            M += 1e-10 * np.trace(M, axis1=1, axis2=2)[:, None, None] * np.eye(3)
            c = np.linalg.solve(M, np.einsum("nki,nk->ni", A, rhs)[..., None])[..., 0]
            radius = hh * np.sqrt(np.maximum(c[:, 2] + c[:, 0] ** 2 + c[:, 1] ** 2, 0.0))
            c[:, :2] = p + hh[:, None] * c[:, :2]
            normal = self.slot_normal[slots]
            toward = np.einsum("ni,ni->n", c[:, :2] - p, normal)
            hole = (valid.sum(1) >= 3) & (radius < HOLE_RADII * hh) & (toward > 0.5 * radius)
            out[slots[hole], :2] = c[hole, :2]
            out[slots[hole], 2] = radius[hole]
        return out


def _loops(edges: np.ndarray, n: int) -> list[np.ndarray]:
    """The boundary loops as sequences of edge indices."""
    out_edge = np.full(n, -1)
    out_edge[edges[:, 0]] = np.arange(len(edges))
    seen = np.zeros(len(edges), dtype=bool)
    loops = []
    for start in range(len(edges)):
        if seen[start]:
            continue
        loop, k = [], start
        while k >= 0 and not seen[k]:
            seen[k] = True
            loop.append(k)
            k = out_edge[edges[k, 1]]
        loops.append(np.array(loop))
    return loops


def _cut(tangent: np.ndarray, loop: np.ndarray) -> list[tuple[np.ndarray, bool]]:
    """A loop of edges cut at its corners: (edge indices, closed) per piece."""
    t_in, t_out = tangent[np.roll(loop, 1)], tangent[loop]
    corner = np.einsum("ij,ij->i", t_in, t_out) < np.cos(np.radians(CORNER_DEGREES))
    if not corner.any():
        return [(loop, True)]
    starts = np.flatnonzero(corner)  # the node at the start of edge k is a corner
    rolled = np.roll(loop, -starts[0])
    starts = starts - starts[0]
    ends = np.r_[starts[1:], len(loop)]
    return [(rolled[a:b], False) for a, b in zip(starts, ends, strict=True)]


def _arc_windows(s: np.ndarray, half: np.ndarray, total: float | None):
    """For every point of a piece at arc lengths ``s``: the indices of the points within
    ``half`` of it along the arc (periodic if ``total``), padded; (idx, valid)."""
    m = len(s)
    if total is not None:  # a closed piece: look at three copies of the arc
        ext = np.concatenate([s - total, s, s + total])
        ids = np.tile(np.arange(m), 3)
    else:
        ext, ids = s, np.arange(m)
    lo = np.searchsorted(ext, s - half, side="left")
    hi = np.searchsorted(ext, s + half, side="right")
    width = max(int((hi - lo).max()), 1)
    k = lo[:, None] + np.arange(width)[None, :]
    valid = k < hi[:, None]
    k = np.minimum(k, len(ext) - 1)
    idx = ids[k]
    if total is not None:  # no point twice (a window longer than the loop)
        valid &= np.abs(ext[k] - s[:, None]) <= 0.5 * total
    return idx, valid


def _smooth_along(s, values, weight, radius, total):
    """Local linear fits of ``values`` (..., m, 2) against arc length, kernel weights
    ``(1 - (ds / radius)^2)^2 * weight``, evaluated at every point."""
    idx, valid = _arc_windows(s, radius, total)
    ds = s[idx] - s[:, None]
    if total is not None:
        ds = (ds + 0.5 * total) % total - 0.5 * total
    r = np.abs(ds) / radius[:, None]
    w = np.where(valid & (r < 1), (1 - r * r) ** 2, 0.0) * weight[idx]
    m0, m1, m2 = w.sum(1), (w * ds).sum(1), (w * ds * ds).sum(1)
    det = m0 * m2 - m1 * m1
    ok = det > 1e-12 * np.maximum(m0 * m2, 1e-300)
    v = values[..., idx, :]  # (..., m, k, c)
    b0 = np.einsum("mk,...mkc->...mc", w, v)
    b1 = np.einsum("mk,...mkc->...mc", w * ds, v)
    lin = (m2[:, None] * b0 - m1[:, None] * b1) / np.where(ok, det, 1.0)[:, None]
    # too few points for a line (a piece of one or two edges): the weighted mean
    mean = b0 / np.maximum(m0, 1e-300)[:, None]
    return np.where(ok[:, None], lin, mean)
