#!/usr/bin/env bash
# Kalthoff-Winkler edge-on impact, 2D plane strain (benchmarks.md section 2).
#   VARIANT=quick|demo: dx = 1 mm   (20,000 particles, well under a minute on 2 cores)
#   VARIANT=full      : dx = 0.5 mm (80,000 particles, a few minutes)
#   VARIANT=test      : dx = 1.25 mm, 60 us (12,800 particles; the CTest regression run:
#                       case-quick.yaml's variant `test`)
# Environment: BRECCIA_BIN (executables), OUT (output folder), PYTHON, THREADS (optional).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
OPTIONS=()
case "$VARIANT" in
  quick|demo) DX=0.001;  DECK=case-quick.yaml ;;
  full)       DX=0.0005; DECK=case-full.yaml ;;
  test)       DX=0.00125; DECK=case-quick.yaml; OPTIONS=(--variant test) ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full|test)" >&2; exit 2 ;;
esac
mkdir -p "$OUT/run"
"$BRECCIA_BIN/breccia-place" --lattice square --box 0,0,0.1,0.2 --spacing "$DX" --thickness 9mm \
  -o "$OUT/particles.h5" > "$OUT/place.log"
"$BRECCIA_BIN/breccia-solve" "$HERE/$DECK" -o "$OUT/run" --set "specimen.particles=$OUT/particles.h5" "${OPTIONS[@]}" \
  --threads "$THREADS" --quiet
"$BRECCIA_BIN/breccia-post" "$OUT/run" --cracks --energy --quiet > "$OUT/run/post.log"
"$PYTHON" "$HERE/report.py" "$OUT" run
echo "report: $OUT/report.json; pictures: $OUT/*.png"
