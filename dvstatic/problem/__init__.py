"""The problem: supports and loads (:class:`Fix`, :class:`Traction`, :class:`Pressure`,
:class:`BodyForce`, :class:`PointLoad`), the constrained dofs and the load vector
(layer 3).

``where`` selects nodes or boundary edges: a part name of the mesh (``"left"``,
``"right"``, ``"bottom"``, ``"top"`` for rectangles), an index array of nodes
(:class:`Fix`, :class:`PointLoad`), or an (m, 2) array of boundary edges
(:class:`Traction`, :class:`Pressure`). Loads are given per unit thickness.
"""

from ..linalg import check_restrained
from .fields import evaluate
from .follower import FollowerPressures
from .loads import (
    LOADS,
    BodyForce,
    PointLoad,
    Pressure,
    Traction,
    load_vector,
    nodal_forces,
)
from .problem import Problem
from .scale import scaled
from .select import At, as_list, nearest_node, select_edges, select_nodes
from .supports import Fix, SupportComponent, constraints, support_components

__all__ = [
    "Problem",
    "scaled",
    "Fix",
    "Traction",
    "Pressure",
    "BodyForce",
    "PointLoad",
    "At",
    "nearest_node",
    "LOADS",
    "evaluate",
    "as_list",
    "select_nodes",
    "select_edges",
    "SupportComponent",
    "support_components",
    "constraints",
    "check_restrained",
    "load_vector",
    "nodal_forces",
    "FollowerPressures",
]
