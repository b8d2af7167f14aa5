#!/usr/bin/env bash
# Install the optional PETSc backend of dvstatic (the dvstatic[petsc] extra) into a venv:
# MPI (the mpich wheel), mpi4py, PETSc (compiled from PyPI's source distribution: about
# 8-10 minutes on 2 cores) and petsc4py (about 5 minutes), then dvstatic itself.
#
#   bash scripts/install_petsc.sh [VENV]        # default VENV: .venv (created if missing)
#
# PETSc needs BLAS/LAPACK: on Debian/Ubuntu this script installs libopenblas-dev and
# liblapack-dev with apt-get when it runs as root; elsewhere install them first (or set
# PETSC_CONFIGURE_OPTIONS="--with-blaslapack-dir=..."). CUDA/HIP are switched off: the
# backend is for CPU clusters. Extra PETSc configure options can be passed in
# PETSC_CONFIGURE_OPTIONS.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${1:-.venv}
[ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
PY="$VENV/bin/python"
export PATH="$(cd "$VENV/bin" && pwd):$PATH"

if ! ldconfig -p 2>/dev/null | grep -q "liblapack.so "; then
  if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
    apt-get install -y -q --no-install-recommends libopenblas-dev liblapack-dev >/dev/null \
      || { apt-get update -q >/dev/null && apt-get install -y -q --no-install-recommends libopenblas-dev liblapack-dev >/dev/null; }
  else
    echo "PETSc needs BLAS/LAPACK: install libopenblas-dev and liblapack-dev (or equivalent) first" >&2
    exit 1
  fi
fi

"$PY" -m pip install -q mpich mpi4py
# --no-cache-dir: what PETSc's build finds (MPI on PATH, BLAS) is not part of pip's wheel
# cache key, so a wheel cached from another environment (e.g. without MPI) must not be reused
PETSC_CONFIGURE_OPTIONS="--with-cuda=0 --with-hip=0 --with-x=0 COPTFLAGS=-O2 CXXOPTFLAGS=-O2 ${PETSC_CONFIGURE_OPTIONS:-}" \
  "$PY" -m pip install -q --no-cache-dir petsc
# petsc4py builds against the PETSc just installed (otherwise pip would build PETSc again)
PETSC_DIR=$("$PY" -c "import petsc; print(petsc.get_petsc_dir())") \
  "$PY" -m pip install -q --no-cache-dir petsc4py
"$PY" -m pip install -q ".[petsc,test]"
# smoke test: two ranks see each other (fails on a PETSc built without MPI)
"$VENV/bin/mpiexec" -n 2 "$PY" -c "from petsc4py import PETSc; assert PETSc.COMM_WORLD.getSize() == 2"
"$PY" -c "from petsc4py import PETSc; print('PETSc', '.'.join(map(str, PETSc.Sys.getVersion())), 'with MPI: ready')"
