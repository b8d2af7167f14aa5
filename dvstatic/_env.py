"""Facts about the running process, read without importing optional packages."""

from __future__ import annotations

import os

__all__ = ["launched_under_mpi"]

_MPI_SIZE_VARIABLES = ("PMI_SIZE", "OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS")


def launched_under_mpi() -> bool:
    """True if this process was started by an MPI launcher (``mpiexec``), read from
    the launcher's environment without importing MPI."""
    for key in _MPI_SIZE_VARIABLES:
        v = os.environ.get(key, "")
        if v.isdigit() and int(v) >= 1:
            return True
    return False
