#!/usr/bin/env bash
# make lammps-peri: LAMMPS PERI's projectile examples in LAMMPS and in Breccia side by side
# (scripts/lammps_peri.py; docs/lammps-peri.md). Installs Debian's lammps if it is missing.
# Usage: scripts/lammps_peri.sh BUILD_DIR [extra arguments of lammps_peri.py]
set -euo pipefail
BUILD=${1:-build}; shift || true
if ! command -v lmp >/dev/null 2>&1; then
  echo "lammps-peri: installing LAMMPS (Debian package lammps) for the side-by-side comparison"
  SUDO=""; [ "$(id -u)" != 0 ] && SUDO=sudo
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends lammps >/dev/null
fi
exec "${PYTHON:-/usr/bin/python3}" "$(dirname "$0")/lammps_peri.py" --build "$BUILD" --out "${OUT:-runs/lammps-peri}" "$@"
