"""Meshes: the :class:`Mesh` container, domains, generators, periodic samples,
perturbation and orderings (layer 1: imports only the foundation modules).

``dv.mesh.rectangle``, ``polygon``, ``disc``, ``generate`` mesh a domain;
``dv.mesh.periodic_square`` makes a periodic sample; :meth:`Mesh.perturbed` and
:func:`with_spread` raise the irregularity of a mesh.
"""

from .core import Mesh
from .domain import Arc, Circle, Domain, EllipseArc, Line, Path, Polygon, rectangle_domain
from .generators import KINDS, disc, generate, lloyd, polygon, rectangle, with_spread
from .graded import size_near
from .locate import interpolate
from .ordering import mesh_dof_order, spatial_order
from .periodic import periodic_sample, periodic_square
from .recipe import Sampling
from .topology import Topology

__all__ = [
    "Mesh",
    "Topology",
    "Circle",
    "Domain",
    "Polygon",
    "Path",
    "Line",
    "Arc",
    "EllipseArc",
    "rectangle_domain",
    "KINDS",
    "rectangle",
    "polygon",
    "disc",
    "generate",
    "lloyd",
    "with_spread",
    "size_near",
    "periodic_square",
    "periodic_sample",
    "Sampling",
    "interpolate",
    "mesh_dof_order",
    "spatial_order",
]
