#!/usr/bin/env bash
# Colliding rubber rings (benchmarks.md section 10): two elastic rings meet at 2 x 50.3 m/s,
# rebound and separate. Runs the stress-based MPS solid, then plots the rings at several
# times and the energy history (rings.png) and writes rings.json (rebound speed, energy).
#   VARIANT=quick: spacing 2 mm (5 circles through the wall, 1,100 particles, ~10 s)
#   VARIANT=demo : 1 mm (10 circles, 4,400 particles, ~2-6 min on 2 shared cores)
#   VARIANT=full : 0.5 mm (20 circles, 17,600 particles, ~30+ min)
# BACKEND=cuda runs through breccia-solve on a GPU; default cpu.
set -euo pipefail
: "${BRECCIA_BIN:?path to the Breccia executables}" "${OUT:?output directory}"
VARIANT=${VARIANT:-quick}
PYTHON=${PYTHON:-/usr/bin/python3}
HERE="$(cd "$(dirname "$0")" && pwd)"
case "$VARIANT" in  # quick and full: variants of case.yaml; demo: case.yaml as shipped
  quick) SPACING=2;   OPTIONS=(--variant quick) ;;   # snapshots every ~0.12 ms
  demo)  SPACING=1;   OPTIONS=() ;;
  full)  SPACING=0.5; OPTIONS=(--variant full) ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full)" >&2; exit 2 ;;
esac
THREADS=${THREADS:-$(nproc)}
# BACKEND=cuda|auto: the stress launcher (docs/cuda.md "MPS"), not yet run on a GPU.
mkdir -p "$OUT"
"$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$OUT/rings_h${SPACING}mm" "${OPTIONS[@]}" --backend "${BACKEND:-cpu}" \
  --threads "$THREADS"
"$PYTHON" "$HERE/plot_rings.py" "$OUT/rings_h${SPACING}mm" "$OUT/rings.png" "$OUT/rings.json"
echo "figure and numbers in $OUT (rings.png, rings.json)"
