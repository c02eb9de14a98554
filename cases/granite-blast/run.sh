#!/usr/bin/env bash
# Single-hole blast in granite, 2D plane strain (benchmarks.md section 4).
#   VARIANT=quick|demo: dx = 0.5 mm  (16,000 particles)
#   VARIANT=full      : dx = 0.25 mm (65,000 particles; the seed's spacing)
#   VARIANT=test      : dx = 0.5 mm, 25 us (the CTest regression run)
# Environment: BRECCIA_BIN (executables), OUT (output folder), PYTHON, THREADS (optional),
# OUTPUT_EVERY (optional: steps between outputs, for a finer crack-length history).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
case "$VARIANT" in
  quick|demo) DX=0.0005;  OPTIONS=() ;;                         # outputs ~2.4 us apart
  full)       DX=0.00025; OPTIONS=(--set output.every=50) ;;
  test)       DX=0.0005;  OPTIONS=(--set "time.end=25 us") ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full|test)" >&2; exit 2 ;;
esac
[ -z "${OUTPUT_EVERY:-}" ] || OPTIONS+=(--set "output.every=$OUTPUT_EVERY")
mkdir -p "$OUT"
"$PYTHON" "$HERE/specimen.py" "$OUT/particles.h5" --outer 0.036 --inner 0.0012875 --spacing "$DX" --thickness 0.001
# Runs, each a variant of case.yaml: g0_200 (as shipped: G0 = 200 J/m2, the textbook critical
# stretch) and seed_s0 (G0 = 200/pi J/m2, the critical stretch of [Fukuda PD]'s formula, which
# carries an extra 1/sqrt(pi), benchmarks.md section 0.6: a labelled sensitivity run, not a
# calibration). On request (GRANITE_RUNS=...): softening (G0 = 200 J/m2 and a tensile strength,
# STRENGTH, default 12 MPa, a placeholder, through softening bonds: docs/theory.md "Quasi-brittle
# bonds"; README.md; softening_sqrt and softening_none: the strength x the square root of each
# bond's G0 draw, or not scattered: docs/theory.md "Weibull heterogeneity"; softening_rate,
# softening_gas, softening_rate_gas: softening_sqrt with fib's rate law and/or the gas load) and gas
# (the borehole history as a gas load's closed-cavity pressure: docs/theory.md "Borehole gas"; README.md).
RUNS=()
for run in ${GRANITE_RUNS:-g0_200 seed_s0}; do
  extra=()
  [ "${run#softening}" = "$run" ] || [ -z "${STRENGTH:-}" ] || extra=(--set "materials[0].tensile_strength=$STRENGTH")
  echo "== $run"
  "$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$OUT/$run" --set "specimen.particles=$OUT/particles.h5" \
    --variant "$run" "${OPTIONS[@]}" "${extra[@]}" --threads "$THREADS" --quiet
  "$BRECCIA_BIN/breccia-post" "$OUT/$run" --cracks --fragments --energy --quiet > "$OUT/$run/post.log"
  RUNS+=("$run")
done
"$PYTHON" "$HERE/report.py" "$OUT" "${RUNS[@]}"
echo "report: $OUT/report.json; pictures: $OUT/*.png"
