"""Loads: :class:`Traction`, :class:`Pressure`, :class:`BodyForce`, :class:`PointLoad`,
and the nodal forces they give.

All loads are dead loads given per unit thickness (a model's ``thickness`` turns the
distributed ones into totals), except follower pressures in nonlinear solves
(:mod:`.follower`). Values may be functions of position, evaluated at quadrature
points and checked (:func:`evaluate`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._checks import check_real, check_vector2
from ..errors import InputError
from ..mesh import Mesh
from .fields import evaluate, vector_or_callable
from .select import as_list, label, select_edges, select_nodes, where_ok
from .supports import Fix, _at_where

__all__ = [
    "Traction",
    "Pressure",
    "BodyForce",
    "PointLoad",
    "LOADS",
    "nodal_forces",
    "load_vector",
]


@dataclass(frozen=True, eq=False)
class Traction:
    """Distributed force per unit boundary length on boundary edges.

    Parameters
    ----------
    where : str or array_like of int, shape (m, 2)
        Part name or boundary edges.
    value : (tx, ty) or callable
        Force per unit length (force / length; stress units for unit thickness), or
        a function of position ``t(x) -> (m, 2)``. Constant values are lumped half to
        each end node of every edge; functions are integrated with the linear shape
        functions of each edge and two Gauss points (exact resultant and moment for
        linearly varying tractions).
    """

    where: object
    value: object

    def __post_init__(self) -> None:
        where_ok(self.where, "Traction", nodes=False)
        object.__setattr__(self, "value", vector_or_callable(self.value, "Traction value"))


@dataclass(frozen=True, eq=False)
class Pressure:
    """Normal pressure on boundary edges; positive pushes into the body.

    Parameters
    ----------
    where : str or array_like of int, shape (m, 2)
        Part name or boundary edges.
    p : float or callable
        Pressure (force per unit length for unit thickness, i.e. stress units), or a
        function of position ``p(x) -> (m,)`` (e.g. hydrostatic). The force on an
        edge is ``-p n`` per unit length, ``n`` its outward normal, lumped with the
        edge's linear shape functions (exact resultant on any polygonal boundary).
    follower : bool
        Nonlinear solves: the pressure stays normal to the deformed edges and scales
        with their current length (its derivative enters the Newton tangent, which is
        then not symmetric). Linear solves use the reference edges either way.
    """

    where: object
    p: object
    follower: bool = False

    def __post_init__(self) -> None:
        where_ok(self.where, "Pressure", nodes=False)
        if not callable(self.p):
            object.__setattr__(self, "p", check_real("Pressure p", self.p))
        if not isinstance(self.follower, (bool, np.bool_)):
            raise TypeError(f"Pressure follower must be True or False, got {self.follower!r}")
        object.__setattr__(self, "follower", bool(self.follower))


@dataclass(frozen=True, eq=False)
class BodyForce:
    """Force per unit area, e.g. ``BodyForce((0, -rho g))``.

    Parameters
    ----------
    value : (bx, by) or callable
        Constant, lumped to the nodes with one third of the area of each neighbouring
        triangle (the consistent lumping of P1 elements; the nodal forces sum to
        ``value * area``), or a function of position ``b(x) -> (m, 2)`` integrated
        over each triangle with the edge-midpoint rule (exact for linear variation).
    region : str, optional
        Only on the triangles of this region of the mesh (``mesh.regions``), e.g. the
        weight of one layer.
    """

    value: object
    region: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", vector_or_callable(self.value, "BodyForce value"))
        if self.region is not None and not isinstance(self.region, str):
            raise TypeError(f"BodyForce region must be a region name, got {self.region!r}")


@dataclass(frozen=True, eq=False)
class PointLoad:
    """Concentrated force ``value`` applied to each of the selected nodes.

    Parameters
    ----------
    nodes : str, array_like of int or At
        Part name, node indices (every node receives the full ``value``), or
        :class:`At` (the node nearest to a point).
    value : (fx, fy)
        Force per node (force per unit thickness).
    at : (x, y), optional
        Instead of ``nodes``: the node nearest to this point (length), within the
        local spacing of it (``PointLoad(at=(0.0, 1.0), value=(0.0, -1.0))``).
    """

    nodes: object = None
    value: tuple[float, float] | None = None
    at: object = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "nodes", _at_where(self.nodes, self.at, "PointLoad", "nodes"))
        if self.value is None:
            raise TypeError("PointLoad: `value` (fx, fy) is required")
        where_ok(self.nodes, "PointLoad")
        object.__setattr__(self, "value", tuple(check_vector2("PointLoad value", self.value)))


LOADS = (Traction, Pressure, BodyForce, PointLoad)


#: two-point Gauss rule on [0, 1]: abscissae and weights
_GAUSS_S = 0.5 + np.array([-0.5, 0.5]) / np.sqrt(3.0)
_GAUSS_W = np.array([0.5, 0.5])


def _edge_forces(mesh: Mesh, e: np.ndarray, density) -> tuple[np.ndarray, np.ndarray]:
    """Nodal forces of a force density along edges ``e``: ``density(x, n) -> (k, 2)``
    evaluated at two Gauss points of every edge (``n``: outward unit normals), lumped
    with the edges' linear shape functions."""
    xa, xb = mesh.points[e[:, 0]], mesh.points[e[:, 1]]
    d = xb - xa
    length = np.hypot(d[:, 0], d[:, 1])
    normal = np.c_[d[:, 1], -d[:, 0]] / length[:, None]
    m = len(e)
    xq = (xa[None] + _GAUSS_S[:, None, None] * d[None]).reshape(-1, 2)
    tq = density(xq, np.tile(normal, (2, 1))).reshape(2, m, 2)
    fa = np.einsum("q,q,qmc->mc", _GAUSS_W, 1.0 - _GAUSS_S, tq) * length[:, None]
    fb = np.einsum("q,q,qmc->mc", _GAUSS_W, _GAUSS_S, tq) * length[:, None]
    return np.concatenate([e[:, 0], e[:, 1]]), np.concatenate([fa, fb])


def _load_terms(mesh: Mesh, load):
    """Nodal contributions of one load: node indices (k,) and forces (k, 2)."""
    if isinstance(load, Traction):
        e = select_edges(mesh, load.where, "Traction")
        if callable(load.value):
            what = f"Traction on {label(load.where)}"
            return _edge_forces(mesh, e, lambda x, n: evaluate(load.value, x, (2,), what))
        d = mesh.points[e[:, 1]] - mesh.points[e[:, 0]]
        half = 0.5 * np.hypot(d[:, 0], d[:, 1])
        nodes = np.concatenate([e[:, 0], e[:, 1]])
        return nodes, np.concatenate([half, half])[:, None] * np.asarray(load.value)[None, :]
    if isinstance(load, Pressure):
        e = select_edges(mesh, load.where, "Pressure")
        what = f"Pressure on {label(load.where)}"
        if callable(load.p):
            return _edge_forces(mesh, e, lambda x, n: -evaluate(load.p, x, (), what)[:, None] * n)
        return _edge_forces(mesh, e, lambda x, n: -load.p * n)
    if isinstance(load, BodyForce):
        return _body_terms(mesh, load)
    if isinstance(load, PointLoad):
        nodes = select_nodes(mesh, load.nodes, "PointLoad")
        return nodes, np.broadcast_to(np.asarray(load.value), (nodes.size, 2))
    if isinstance(load, Fix):
        raise TypeError("Fix is a support: pass it in `supports`, not in `loads`")
    raise TypeError(
        f"unknown load type {type(load).__name__}; use Traction, Pressure, BodyForce or PointLoad"
    )


def _body_terms(mesh: Mesh, load: BodyForce):
    """Constant: a third of every triangle to each vertex; a function: the edge-midpoint
    rule with the linear shape functions (exact for linear variation)."""
    sel = slice(None)
    if load.region is not None:
        if load.region not in mesh.regions:
            known = ", ".join(repr(k) for k in mesh.regions) or "none"
            raise InputError(
                f"BodyForce: unknown region {load.region!r}; the mesh's regions: {known}",
                "region",
            )
        sel = mesh.regions[load.region]
    tri = mesh.triangles[sel]
    area = mesh.triangle_areas[sel]
    if not callable(load.value):
        share = np.repeat(area / 3.0, 3)
        return tri.ravel(), share[:, None] * np.asarray(load.value)[None, :]
    x = mesh.triangle_coordinates()[sel]
    mid = 0.5 * (x[:, [1, 2, 0]] + x[:, [2, 0, 1]])  # midpoint of the edge opposite vertex k
    b = evaluate(load.value, mid.reshape(-1, 2), (2,), "BodyForce").reshape(-1, 3, 2)
    # vertex v gets A/6 (b at the midpoints of its two edges)
    f = (area / 6.0)[:, None, None] * (b.sum(axis=1, keepdims=True) - b)
    return tri.ravel(), f.reshape(-1, 2)


def nodal_forces(
    mesh: Mesh, loads, nodes: np.ndarray | None = None, thickness: float = 1.0
) -> np.ndarray:
    """External forces on ``nodes`` (all nodes if None), interleaved, shape (2 len(nodes),).

    Constant tractions are lumped half to each end node of every edge (exact for the
    resultant and the moment about each edge's midpoint), varying ones and pressures
    with the edges' linear shape functions; body forces with one third of the area of
    each neighbouring triangle (the consistent lumping of P1 elements); point loads go
    to their nodes. Distributed loads are multiplied by ``thickness`` (point loads are
    totals already). The distributed engine asks for its own nodes only.
    """
    n = mesh.n_points
    if nodes is None:
        local = np.arange(n)
        m = n
    else:
        local = np.full(n, -1, dtype=np.int64)
        local[nodes] = np.arange(len(nodes))
        m = len(nodes)
    f = np.zeros((m, 2))
    for load in as_list(loads, "Traction, Pressure, BodyForce or PointLoad"):
        where, values = _load_terms(mesh, load)
        if thickness != 1.0 and not isinstance(load, PointLoad):
            values = thickness * values
        k = local[where]
        keep = k >= 0
        for c in range(2):
            f[:, c] += np.bincount(k[keep], values[keep, c], m)
    return f.reshape(-1)


def load_vector(mesh: Mesh, loads, scale: float = 1.0, thickness: float = 1.0) -> np.ndarray:
    """External nodal forces, interleaved, shape (2N,).

    Parameters
    ----------
    mesh : Mesh
    loads : Traction, Pressure, BodyForce, PointLoad or a list of them
    scale : float
        Load factor applied to all loads.
    thickness : float
        Multiplies the distributed loads (forces per unit area / volume) into totals.
    """
    return scale * nodal_forces(mesh, loads, thickness=thickness)
