#!/usr/bin/env bash
# Dynamic crack branching in Homalite-100 (Bobaru & Zhang 2015 section 5.2; benchmarks.md 1b).
#   VARIANT=full : dx = 1 mm, 401 x 209 = 83,809 particles, delta = 4.015 dx (the seed's set-up)
#   VARIANT=quick: dx = 2 mm, 201 x 105 particles (case.yaml as shipped)
#   VARIANT=test : dx = 4 mm, 101 x 53 particles (the CTest regression run, < 30 s)
# full and test are variants of case.yaml (the notch line and output interval follow dx).
# END (optional, e.g. "200 us"): another end time than the 400 us of case.yaml.
# Environment: BRECCIA_BIN (executables), OUT (output folder), PYTHON, THREADS (optional).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
case "$VARIANT" in
  full)       DX=0.001; OPTIONS=(--variant full) ;;
  quick|demo) DX=0.002; OPTIONS=() ;;
  test)       DX=0.004; OPTIONS=(--variant test) ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full|test)" >&2; exit 2 ;;
esac
[ -z "${END:-}" ] || OPTIONS+=(--set "time.end=$END")
mkdir -p "$OUT/run"
# Lattice of cell centres on the nodes i dx (x: 0 ... 0.4 m) and j dx (y: -4 dx ... 0.2 m + 4 dx):
# the 0.4 x 0.2 m plate plus 4 loading rows above and below (401 x 209 at dx = 1 mm).
box=$("$PYTHON" -c "d=$DX; print(f'{-d/2!r},{-4.5*d!r},{0.4+d/2!r},{0.2+4.5*d!r}')")
"$BRECCIA_BIN/breccia-place" --lattice square --box "$box" --spacing "$DX" --thickness 1mm \
  -o "$OUT/particles.h5" > "$OUT/place.log"
"$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$OUT/run" --set "specimen.particles=$OUT/particles.h5" "${OPTIONS[@]}" \
  --threads "$THREADS" --quiet
"$BRECCIA_BIN/breccia-post" "$OUT/run" --cracks --energy --quiet > "$OUT/run/post.log"
"$PYTHON" "$HERE/report.py" "$OUT" run
echo "report: $OUT/report.json; pictures: $OUT/*.png"
