#!/usr/bin/env bash
# Plate with random stiff, strong inclusions (seed's dual-horizon case; benchmarks.md section 3).
#   VARIANT=full : dx = 15 um (201 x 207 = 41,607 particles, the seed's), 2 m/s
#   VARIANT=quick: dx = 30 um (101 x 107 = 10,807 particles), 2 m/s and the 0.1 m/s stand-in
#   VARIANT=test : dx = 30 um, 2 m/s only (the CTest regression run)
# RATES (optional): space-separated "rate_m_s:ramp:end" triples overriding the defaults.
# The seed's slow rate, 0.001 m/s, needs ~10^7 steps at dx = 15 um; it is
# replaced by 0.1 m/s ramped over 2 us, to 16 us (quick only; README: what it stands for).
# full is case.yaml's variant `full` (the notch line follows dx); each rate is given as --set
# (the quick variant's 0.1 m/s run is also case.yaml's variant `slow`).
# Environment: BRECCIA_BIN (executables), OUT (output folder), PYTHON, THREADS (optional).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
case "$VARIANT" in
  full)       DX=15e-6; OPTIONS=(--variant full); RATES=${RATES:-"2:0.1us:1.5us"} ;;
  quick|demo) DX=30e-6; OPTIONS=();               RATES=${RATES:-"2:0.1us:1.5us 0.1:2us:16us"} ;;
  test)       DX=30e-6; OPTIONS=();               RATES="2:0.1us:1.5us" ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full|test)" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
"$PYTHON" "$HERE/specimen.py" "$OUT/particles.h5" --spacing "$DX" > "$OUT/specimen.log"
cat "$OUT/specimen.log"
RUNS=()
for r in $RATES; do  # rate_m_s:ramp:end, given to case.yaml as --set
  IFS=: read -r rate ramp end <<< "$r"
  name="v${rate}"
  options=(--set "boundary[0].value=[0, $rate, 0]" --set "boundary[1].value=[0, -$rate, 0]"
           --set "boundary[0].ramp_time=${ramp/us/ us}" --set "boundary[1].ramp_time=${ramp/us/ us}" --set "time.end=${end/us/ us}")
  echo "== $name"
  "$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$OUT/$name" --set "specimen.particles=$OUT/particles.h5" \
    "${OPTIONS[@]}" "${options[@]}" --threads "$THREADS" --quiet
  "$BRECCIA_BIN/breccia-post" "$OUT/$name" --cracks --quiet > "$OUT/$name/post.log"
  RUNS+=("$name")
done
"$PYTHON" "$HERE/report.py" "$OUT" "${RUNS[@]}"
echo "report: $OUT/report.json; pictures: $OUT/*.png"
