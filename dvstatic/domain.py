"""Planar domains with named boundary curves and regions (``dv.domain.Polygon``,
``Circle``, ``Path`` of ``Line`` / ``Arc`` / ``EllipseArc`` curves, ``Domain``): the
public name of :mod:`dvstatic.mesh.domain`."""

from .mesh.domain import (
    Arc,
    Circle,
    Domain,
    EllipseArc,
    Line,
    Loop,
    Path,
    Polygon,
    rectangle_domain,
)

__all__ = [
    "Polygon",
    "Circle",
    "Path",
    "Line",
    "Arc",
    "EllipseArc",
    "Domain",
    "Loop",
    "rectangle_domain",
]
