"""Distributed solves (layer 4, beside the solvers it builds on): the partition and
per-rank patches (:mod:`.partition`) and the PETSc engine (:mod:`.petsc`, imported only
when ``solver="petsc"`` asks for it)."""

from .partition import (
    Layout,
    available,
    launched_under_mpi,
    layout,
    micro_parameters,
    owned_bonds,
    owned_loads,
    owned_triangles,
    patch_bond_weights,
    patch_memory,
    patch_model,
    patch_triangles,
    rcb_partition,
)

__all__ = [
    "available",
    "launched_under_mpi",
    "rcb_partition",
    "Layout",
    "layout",
    "owned_bonds",
    "owned_triangles",
    "micro_parameters",
    "owned_loads",
    "patch_bond_weights",
    "patch_memory",
    "patch_model",
    "patch_triangles",
]
