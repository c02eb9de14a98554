#!/usr/bin/env bash
# Run one case end to end. One script for both trees:
#   source tree:  scripts/run_case.sh BUILD_DIR CASE [VARIANT [OUT]]   (make demo, make case-NAME)
#   installed:    breccia-run-case CASE [VARIANT [OUT]]                 (<prefix>/bin, cmake --install or the .deb)
# CASE: a case name (a folder of the tree's cases/) or a path to a case folder.
# VARIANT: quick (CI-sized, minutes on 2 cores), demo, or full (the published resolution).
# OUT: the output folder (also from $OUT; default ./runs/NAME-VARIANT).
# Each case folder holds run.sh, which uses the tools in $BRECCIA_BIN and writes to $OUT.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
usage() {
  echo "usage: scripts/run_case.sh BUILD_DIR CASE [VARIANT [OUT]]  or, installed: breccia-run-case CASE [VARIANT [OUT]]" >&2
  exit 2
}
# Installed as <prefix>/bin/breccia-run-case: the tools are beside it and the cases in
# <prefix>/share/breccia; in the source tree (scripts/) both come from the arguments and ../cases.
if [ -d "$HERE/../share/breccia/cases" ]; then
  BRECCIA_BIN="$HERE"
  export BRECCIA_ROOT="$(cd "$HERE/../share/breccia" && pwd)"
else
  [ $# -ge 2 ] || usage
  BUILD=$1; shift
  if [ ! -d "$BUILD/bin" ]; then
    echo "run_case: $BUILD/bin not found (expected a build folder: make build)" >&2
    exit 2
  fi
  BRECCIA_BIN="$(cd "$BUILD/bin" && pwd)"
  export BRECCIA_ROOT="$(cd "$HERE/.." && pwd)"
fi
[ $# -ge 1 ] || usage
CASE=$1; VARIANT=${2:-quick}
case "$CASE" in
  */*) CASE_DIR=$CASE ;;                      # a path
  *)   CASE_DIR="$BRECCIA_ROOT/cases/$CASE" ;;  # a name
esac
if [ ! -f "$CASE_DIR/run.sh" ]; then
  echo "run_case: $CASE_DIR/run.sh not found (expected a case name from $BRECCIA_ROOT/cases or a case folder with run.sh)" >&2
  exit 2
fi
export BRECCIA_BIN VARIANT
OUT=${3:-${OUT:-$(pwd)/runs/$(basename "$CASE_DIR")-$VARIANT}}
mkdir -p "$OUT"
export OUT="$(cd "$OUT" && pwd)"  # run.sh works from its own folder
export PYTHON="${PYTHON:-/usr/bin/python3}"
echo "case $(basename "$CASE_DIR") [$VARIANT] -> $OUT"
cd "$CASE_DIR"
# A run that wrote nothing (an unknown variant refused by run.sh, exit 2) leaves no empty
# output folder behind; whatever a run wrote stays.
rc=0
bash ./run.sh || rc=$?
if [ "$rc" != 0 ] && [ -z "$(ls -A "$OUT")" ]; then rmdir "$OUT"; fi
exit "$rc"
