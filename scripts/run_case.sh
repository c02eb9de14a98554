#!/usr/bin/env bash
# Run one case end to end: scripts/run_case.sh BUILD_DIR cases/NAME VARIANT
# VARIANT: quick (CI-sized, minutes on 2 cores), demo, or full (the published resolution).
# Each case directory holds run.sh, which uses the tools in $BRECCIA_BIN and writes to $OUT.
set -euo pipefail
BUILD=${1:?build dir}; CASE_DIR=${2:?case dir}; VARIANT=${3:-quick}
if [ ! -f "$CASE_DIR/run.sh" ]; then
  echo "run_case: $CASE_DIR/run.sh not found (expected a case directory with run.sh)" >&2
  exit 2
fi
export BRECCIA_BIN="$(cd "$BUILD" && pwd)/bin"
export BRECCIA_ROOT="$(pwd)"
export VARIANT
export OUT="${OUT:-$(pwd)/runs/$(basename "$CASE_DIR")-$VARIANT}"
export PYTHON="${PYTHON:-/usr/bin/python3}"
mkdir -p "$OUT"
echo "case $(basename "$CASE_DIR") [$VARIANT] -> $OUT"
cd "$CASE_DIR"
bash ./run.sh
