#!/usr/bin/env bash
# Grady ring: mean fragment size vs strain rate (benchmarks.md section 7).
#   VARIANT=quick|demo: dx = 0.1 mm  (6,285 particles), rates 5e2 ... 1e4 /s
#   VARIANT=full      : dx = 0.05 mm (25,130 particles), rates 5e2 ... 2e4 /s
#   VARIANT=test      : dx = 0.1 mm, rates 1e3 and 1e4 /s (the CTest regression run)
#   VARIANT=zmr | zmr-fine | zmr-finest | zmr-finest2: softening bonds, tensile_strength 18 MPa
#     (STRENGTH_MPA), dx = 0.1 | 0.05 | 0.025 | 0.0125 mm, ring radius 50 mm, at e = rate / e0 = 0.1, 0.3, 1, 3, 10 (Zhou, Molinari &
#     Ramesh 2006; README.md "Softening bonds against Zhou, Molinari & Ramesh")
# Each rate is case.yaml with its strain rate and end time given as --set (the standard rates are
# also the case file's variants rate_5e2 ... rate_2e4).
# Environment: BRECCIA_BIN (executables), OUT (output folder), PYTHON, THREADS (optional);
#   WIDTH (ring width, m, default 0.0005), RADIUS (zmr variants, m, default 0.05) and END_US
#   (end time, us, instead of the rate's own) for studies; OUTPUT_EVERY (steps): results.h5
#   outputs along the way, each post-processed for fragments (breccia-post --all), so that
#   zmr_settle.py can tell when the fragment count settled.
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
case "$VARIANT" in
  quick|demo) DX=0.0001;  RATES=${RATES:-"5e2 1e3 2e3 5e3 1e4"} ;;
  full)       DX=0.00005; RATES=${RATES:-"5e2 1e3 2e3 5e3 1e4 2e4"} ;;
  test)       DX=0.0001;  RATES="1e3 1e4" ;;
  zmr|zmr-fine|zmr-finest|zmr-finest2)
    case "$VARIANT" in zmr) DX=0.0001 ;; zmr-fine) DX=0.00005 ;; zmr-finest) DX=0.000025 ;; *) DX=0.0000125 ;; esac
    # A radius of ~30 cohesive lengths: the ring's kinetic energy is then (e R / L0)^2 >= 9
    # times the strain energy at the strength even at e = 0.1, so the rate holds until it breaks.
    RADIUS=${RADIUS:-0.05}
    STRENGTH_MPA=${STRENGTH_MPA:-18}
    # e0 = c sigma_t^3 / (E^2 G0), c = sqrt(E / rho): the glass of case.yaml.
    RATES=${RATES:-$("$PYTHON" -c "
import math
E, rho, G0, st = 72e9, 2440.0, 7.8125, $STRENGTH_MPA * 1e6
e0 = math.sqrt(E / rho) * st**3 / (E**2 * G0)
print(' '.join('%.4g' % (e * e0) for e in (0.1, 0.3, 1, 3, 10)))")} ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full|test|zmr|zmr-fine|zmr-finest|zmr-finest2)" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
"$PYTHON" "$HERE/specimen.py" "$OUT/particles.h5" --radius "${RADIUS:-0.02}" --width "${WIDTH:-0.0005}" --spacing "$DX" --thickness 0.001
RUNS=()
for r in $RATES; do
  name="rate_$r"
  # End time: 4 us (several crack-spacing wave transits) after the mean failure strain
  # (~7e-4 at dx 0.1 mm) is reached, counted three times over for the scatter.
  end_us=$("$PYTHON" -c "print(round(4 + 3 * 7e-4 / $r * 1e6, 2))")
  # Softening: 20 us (many release-wave transits of the largest fragment) after 6 times the
  # time to reach the strength's strain. At e >= 3 the kept count still grows after it (the
  # last bonds of early crack bands break for tens of us): those rates are run to a settled
  # count with END_US and OUTPUT_EVERY, then zmr_settle.py (README "Runs to a settled count").
  [ -z "${STRENGTH_MPA:-}" ] || end_us=$("$PYTHON" -c "print(round(20 + 6 * $STRENGTH_MPA * 1e6 / 72e9 / $r * 1e6, 2))")
  end_us=${END_US:-$end_us}
  options=(--set "initial[0].strain_rate=$r" --set "time.end=$end_us us")
  [ -z "${STRENGTH_MPA:-}" ] || options+=(--set "materials[0].tensile_strength=$STRENGTH_MPA MPa")
  [ -z "${OUTPUT_EVERY:-}" ] || options+=(--set "output.every=$OUTPUT_EVERY")
  echo "== $name (end $end_us us)"
  "$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$OUT/$name" --set "specimen.particles=$OUT/particles.h5" "${options[@]}" \
    --threads "$THREADS" --quiet
  # Every output (fragments_<step>.csv, for zmr_settle.py), then the last as report.py reads it.
  [ -z "${OUTPUT_EVERY:-}" ] || "$BRECCIA_BIN/breccia-post" "$OUT/$name" --fragments --all --quiet --no-plots > "$OUT/$name/post_all.log"
  "$BRECCIA_BIN/breccia-post" "$OUT/$name" --fragments --quiet --no-plots > "$OUT/$name/post.log"
  RUNS+=("$name")
done
"$PYTHON" "$HERE/report.py" "$OUT" "${RUNS[@]}"
echo "report: $OUT/report.json; pictures: $OUT/*.png"
