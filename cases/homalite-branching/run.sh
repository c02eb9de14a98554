#!/usr/bin/env bash
# Dynamic crack branching in Homalite-100 (Bobaru & Zhang 2015 section 5.2; benchmarks.md 1b).
#   VARIANT=full : dx = 1 mm, 401 x 209 = 83,809 particles, delta = 4.015 dx (the seed's set-up)
#   VARIANT=quick: dx = 2 mm, 201 x 105 particles
#   VARIANT=test : dx = 4 mm, 101 x 53 particles (the CTest regression run, < 30 s)
# Environment: BRECCIA_BIN (executables), OUT (output folder), PYTHON, THREADS (optional).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
END=${END:-"400 us"}
case "$VARIANT" in
  full)       DX=0.001; EVERY=12 ;;
  quick|demo) DX=0.002; EVERY=6 ;;
  test)       DX=0.004; EVERY=3 ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full|test)" >&2; exit 2 ;;
esac
mkdir -p "$OUT/run"
# Lattice of cell centres on the nodes i dx (x: 0 ... 0.4 m) and j dx (y: -4 dx ... 0.2 m + 4 dx):
# the 0.4 x 0.2 m plate plus 4 loading rows above and below (401 x 209 at dx = 1 mm).
box=$("$PYTHON" -c "d=$DX; print(f'{-d/2!r},{-4.5*d!r},{0.4+d/2!r},{0.2+4.5*d!r}')")
"$BRECCIA_BIN/breccia-place" --lattice square --box "$box" --spacing "$DX" --thickness 1mm \
  -o "$OUT/particles.h5" > "$OUT/place.log"
half=$("$PYTHON" -c "print(0.5*$DX)")
top=$("$PYTHON" -c "print(0.2+0.5*$DX)")
"$PYTHON" "$HERE/../../scripts/add_sets.py" "$OUT/particles.h5" \
  "load_rows_bottom:-1,-1,1,-$half" "load_rows_top:-1,$top,1,1"
# The plate has a particle row on y = 0.1 m: the notch runs half a spacing above it, between rows.
notch_y=$("$PYTHON" -c "print(0.1+0.5*$DX)")
sed -e "s/NOTCH_Y/$notch_y/g" -e "s/end: END/end: $END/" -e "s/every: EVERY/every: $EVERY/" \
    "$HERE/case.yaml" > "$OUT/run/case.yaml"
"$BRECCIA_BIN/breccia-solve" "$OUT/run/case.yaml" -o "$OUT/run" --threads "$THREADS" --quiet
"$BRECCIA_BIN/breccia-post" "$OUT/run" --cracks --energy --quiet > "$OUT/run/post.log"
"$PYTHON" "$HERE/report.py" "$OUT" run
echo "report: $OUT/report.json; pictures: $OUT/*.png"
