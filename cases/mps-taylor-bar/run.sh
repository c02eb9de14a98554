#!/usr/bin/env bash
# Taylor bar (benchmarks.md section 9): copper bar onto a rigid wall at 227 m/s, stress-based
# MPS solid in 3D, at several resolutions; report.py writes the convergence table
# (taylor_convergence.md / .json) and the chart (taylor_convergence.png) against the
# published length and face radius.
#   VARIANT=quick: 8 particles across the diameter (2,080 particles, ~10-30 s)
#   VARIANT=demo : 8 and 16 across (16,848 particles; ~10-20 min on 2 shared cores)
#   VARIANT=full : 8, 16 and 24 across (54,208 particles; ~1 h more on 2 cores)
# ACROSS="8 16" overrides the list; a resolution whose run already finished (summary.json
# present) is not run again, so a full run after a demo run only adds 24 across.
# BACKEND=cuda runs through breccia-solve on the GPU (the stress formulation's launcher,
# docs/cuda.md "MPS"); default cpu (breccia-mps).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
case "$VARIANT" in
  quick) ACROSS=${ACROSS:-"8"} ;;
  demo)  ACROSS=${ACROSS:-"8 16"} ;;
  full)  ACROSS=${ACROSS:-"8 16 24"} ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full)" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
RUNS=()
for n in $ACROSS; do
  name="across${n}"
  dir="$OUT/$name"
  RUNS+=("$dir")
  if [ -f "$dir/summary.json" ] && [ -z "${RERUN:-}" ]; then echo "== $name: done before (RERUN=1 runs it again)"; continue; fi
  mkdir -p "$dir"
  # Spacing = diameter / n in metres (exact: the lattice's layer count rounds length / spacing);
  # snapshots every ~10 us: dt = 0.3 h / c_L, c_L = 4,586 m/s for this copper.
  read -r H EVERY < <("$PYTHON" -c "h = 6.4e-3 / $n; print(repr(h), max(1, int(10e-6 / (0.3 * h / 4586.0))))")
  # (the values of case.yaml's variants across8, across16, across24, for any ACROSS)
  echo "== $name: spacing $H m"
  "$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$dir" --set "specimen.bodies.spacing=$H" --set "output.every=$EVERY" \
    --threads "$THREADS" --backend "${BACKEND:-cpu}" 2>&1 | tee "$dir/log.txt"
done
"$PYTHON" "$HERE/report.py" "$OUT" "${RUNS[@]}"
echo "table and chart: $OUT/taylor_convergence.md, $OUT/taylor_convergence.png"
