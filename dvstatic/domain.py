"""Planar domains with named boundary curves (``dv.domain.Polygon``, ``Circle``,
``Domain``): the public name of :mod:`dvstatic.mesh.domain`."""

from .mesh.domain import Circle, Domain, Loop, Polygon, rectangle_domain

__all__ = ["Polygon", "Circle", "Domain", "Loop", "rectangle_domain"]
