#!/usr/bin/env bash
# Nonlinear ultrasonics with a frictional crack ([MPS harmonics]). Runs the MPS solver with and
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
THREADS=${THREADS:-$(nproc)}
mkdir -p "$OUT"
RUNS=()
for s in $SPACINGS; do
  for crack in crack intact; do
    name="${crack}_h${s}mm"
    # case.yaml at spacing s; intact: its variant without the crack.
    options=(--set "specimen.lattice.spacing=$s mm")
    [ "$crack" = crack ] || options+=(--variant intact)
    echo "== $name"
    "$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$OUT/$name" "${options[@]}" --backend cpu --threads "$THREADS"
    RUNS+=("$name")
  done
done
"$PYTHON" "$HERE/plot_harmonics.py" "$OUT" "${RUNS[@]}"
echo "figures and ratios in $OUT"
