#!/usr/bin/env bash
# Fragmenting cylinder (README.md): the tube, the run, breccia-post's fragments, report.py.
#   VARIANT=quick|demo|test: spacing 1.25 mm (4 particles through the wall)
#   VARIANT=full           : spacing 1 mm (CabanaPD's; 71,200 particles)
# Environment: BRECCIA_BIN (executables), OUT (output folder), PYTHON, THREADS (optional).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
case "$VARIANT" in
  quick|demo|test) DX=0.00125 ;;
  full)            DX=0.001 ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full)" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
"$PYTHON" "$HERE/specimen.py" "$OUT/particles.h5" --spacing "$DX"
# case.yaml as shipped, on the particle file just written.
"$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$OUT/run" --set "specimen.particles=$OUT/particles.h5" --threads "$THREADS" --quiet
"$BRECCIA_BIN/breccia-post" "$OUT/run" --fragments --cracks --energy --quiet > "$OUT/post.log"
"$PYTHON" "$HERE/report.py" "$OUT"
echo "report: $OUT/report.json; pictures: $OUT/*.png"
