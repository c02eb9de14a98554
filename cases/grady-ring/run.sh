#!/usr/bin/env bash
# Grady ring: mean fragment size vs strain rate (benchmarks.md section 7).
#   VARIANT=quick|demo: dx = 0.1 mm  (6,285 particles), rates 5e2 ... 1e4 /s
#   VARIANT=full      : dx = 0.05 mm (25,130 particles), rates 5e2 ... 2e4 /s
#   VARIANT=test      : dx = 0.1 mm, rates 1e3 and 1e4 /s (the CTest regression run)
# Environment: BRECCIA_BIN (executables), OUT (output folder), PYTHON, THREADS (optional).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
case "$VARIANT" in
  quick|demo) DX=0.0001;  RATES=${RATES:-"5e2 1e3 2e3 5e3 1e4"} ;;
  full)       DX=0.00005; RATES=${RATES:-"5e2 1e3 2e3 5e3 1e4 2e4"} ;;
  test)       DX=0.0001;  RATES="1e3 1e4" ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full|test)" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
"$PYTHON" "$HERE/specimen.py" "$OUT/particles.h5" --radius 0.02 --width 0.0005 --spacing "$DX" --thickness 0.001
RUNS=()
for r in $RATES; do
  name="rate_$r"
  mkdir -p "$OUT/$name"
  # End time: 4 us (several crack-spacing wave transits) after the mean failure strain
  # (~7e-4 at dx 0.1 mm) is reached, counted three times over for the scatter.
  end_us=$("$PYTHON" -c "print(round(4 + 3 * 7e-4 / $r * 1e6, 2))")
  sed -e "s/RATE/$r/" -e "s/END_US/$end_us/" -e "s#particles: particles.h5#particles: ../particles.h5#" \
      "$HERE/case.yaml" > "$OUT/$name/case.yaml"
  echo "== $name (end $end_us us)"
  "$BRECCIA_BIN/breccia-solve" "$OUT/$name/case.yaml" -o "$OUT/$name" --threads "$THREADS" --quiet
  "$BRECCIA_BIN/breccia-post" "$OUT/$name" --fragments --quiet --no-plots > "$OUT/$name/post.log"
  RUNS+=("$name")
done
"$PYTHON" "$HERE/report.py" "$OUT" "${RUNS[@]}"
echo "report: $OUT/report.json; pictures: $OUT/*.png"
