#!/usr/bin/env bash
# Installs the Debian packages that building, testing, meshing and validating need, when they
# are missing. Idempotent; needs root (or sudo) only when something is missing.
#   libhdf5-dev pkg-config : the hdf5 crate links Debian's serial HDF5
#   libpetsc-real3.18-dev  : the CG + AMG body solver (cargo feature petsc); brings Open MPI
#   libopenmpi-dev           (pkg-config `mpi`: mpi.h and libmpi, which the PETSc shim needs)
#   openmpi-bin            : mpirun, for distributed runs and their tests (tests/mpi.rs)
#   gmsh python3-gmsh      : mesh generation (geo/), and dolfinx's gmsh reader
#   python3-dolfinx ...    : validation/ (FEniCSx reference), never used by the solver
#   libopenblas0-pthread   : an optimized BLAS for dolfinx and PETSc (the benchmarks time dolfinx's
#                            solvers against ours; Debian's reference BLAS would slow MUMPS)
#   python3-venv python3-pytest : the Python module's environment (build/venv) and its tests
#   python3-meshio         : the Python module's to_meshio() export and its test
#   fonts-dejavu-core      : the font of force_displacement.png (plotters draws text with a font
#                            file read at run time; without it the run skips the PNG and warns)
set -euo pipefail
packages=(pkg-config libhdf5-dev libpetsc-real3.18-dev libopenmpi-dev openmpi-bin libopenblas0-pthread fonts-dejavu-core gmsh python3-gmsh python3-dolfinx python3-h5py python3-scipy python3-matplotlib python3-venv python3-pytest python3-meshio)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
    exit 0
fi
echo "installing: ${missing[*]}"
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
while pgrep -x apt-get >/dev/null || pgrep -x dpkg >/dev/null; do sleep 5; done
$sudo apt-get update
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y "${missing[@]}"
