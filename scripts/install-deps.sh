#!/usr/bin/env bash
# Install the Debian 12 packages Breccia needs that are missing, and say which.
set -euo pipefail
PACKAGES=(
  build-essential cmake pkg-config
  dpkg-dev binutils file      # make package: dpkg-shlibdeps (the .deb's library dependencies; CPack's Debian
                              #   generator needs file for it); check-package: strings
  bsdextrautils time          # make bench: column (its tables) and /usr/bin/time (peak memory)
  libgmsh-dev gmsh            # mesher: OpenCASCADE geometry + tet/tri meshing
  libcgal-dev                 # geometry: exact predicates, AABB trees
  libeigen3-dev               # small dense linear algebra (least squares, 3x3)
  libhdf5-dev                 # particles.h5 / results.h5
  libyaml-cpp-dev             # case and specimen files
  nlohmann-json3-dev          # JSON outputs (summary.json, post.json; common/json_file.hpp): non-finite values as null, strings escaped
  libmuparser-dev             # fields by expression in case files (initial velocity, displacement)
  libvtk9-dev                 # postproc: VTU/VTP output, contouring
  libcli11-dev                # every tool's command line (common/cli.hpp): --help, --version, exit 2 on usage errors
  libgtest-dev                # tests
  openmpi-bin libopenmpi-dev  # distributed runs: mpirun -np N breccia-solve (docs/parallel.md)
  libhdf5-openmpi-dev         # parallel HDF5: with MPI the whole build links it; results.h5 / checkpoint.h5 written collectively
  python3-meshio python3-h5py python3-numpy python3-matplotlib python3-yaml  # converters, charts
)
missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "deps: all ${#PACKAGES[@]} Debian packages present"
  exit 0
fi
echo "deps: installing missing Debian packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "deps: installed ${missing[*]}"
