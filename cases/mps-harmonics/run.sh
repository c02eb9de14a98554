#!/usr/bin/env bash
# Nonlinear ultrasonics with a frictional crack (seed 000). Runs the MPS solver with and
# without the crack at one or more particle spacings, then plots u1 at A and its spectrum.
#   VARIANT=quick: spacing 0.125 mm (320k particles, ~1.5-5 min on 2 cores)
#   VARIANT=demo : 0.25 and 0.125 mm (spacing comparison)
#   VARIANT=full : 0.25, 0.125 and 0.0625 mm (the last ~1.3 M particles, many minutes)
set -euo pipefail
: "${BRECCIA_BIN:?path to the Breccia executables}" "${OUT:?output directory}"
VARIANT=${VARIANT:-quick}
PYTHON=${PYTHON:-/usr/bin/python3}
HERE="$(cd "$(dirname "$0")" && pwd)"
case "$VARIANT" in
  quick) SPACINGS="0.125" ;;
  demo)  SPACINGS="0.25 0.125" ;;
  full)  SPACINGS="0.25 0.125 0.0625" ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full)" >&2; exit 2 ;;
esac
if [ -x "$BRECCIA_BIN/breccia-mps" ]; then SOLVER=("$BRECCIA_BIN/breccia-mps")
else SOLVER=("$BRECCIA_BIN/breccia-solve"); fi
THREADS=${THREADS:-$(nproc)}
mkdir -p "$OUT"
RUNS=()
for s in $SPACINGS; do
  for crack in crack intact; do
    name="${crack}_h${s}mm"
    deck="$OUT/$name.yaml"
    if [ "$crack" = crack ]; then
      sed "s/spacing: 0.25 mm/spacing: $s mm/" "$HERE/case.yaml" > "$deck"
    else  # drop the crack block: everything from the crack-begin marker to boundary:
      sed -e "s/spacing: 0.25 mm/spacing: $s mm/" \
          -e '/# crack-begin/,/^boundary:/{/^boundary:/!d}' "$HERE/case.yaml" > "$deck"
    fi
    echo "== $name"
    "${SOLVER[@]}" "$deck" -o "$OUT/$name" --threads "$THREADS"
    RUNS+=("$name")
  done
done
"$PYTHON" "$HERE/plot_harmonics.py" "$OUT" "${RUNS[@]}"
echo "figures and ratios in $OUT"
