#!/usr/bin/env bash
# Whole-chain benchmark: the concrete-blast case from its gmsh specimen to post-processing,
# each stage timed, at the demo and the full resolution (docs/performance.md, "The whole chain").
# Row per size: mesh, place, solver set-up, mean time step, time loop, post, and the set-up and
# post expressed in time steps (the ratios the performance goals are stated in); also the solve
# command's whole wall time and, of what it spends outside the set-up and the loop, the results
# file's header (particles, bond list) and the final checkpoint (summary.json).
# Usage: scripts/bench_pipeline.sh BUILD_DIR
#   SIZES="demo full"   which specimens (cases/concrete-blast/specimen-SIZE.yaml; full: specimen.yaml)
#   END_US=...          end time of the solve in us (default: the case's own end, so post runs on
#                       the final, most fragmented output; a short END_US times set-up and steps only)
#   THREADS=N           solver and post threads (default: all cores)
set -euo pipefail
BUILD=${1:-build}
HERE="$(cd "$(dirname "$0")/.." && pwd)"
CASE="$HERE/cases/concrete-blast"
PYTHON=${PYTHON:-/usr/bin/python3}
OUT="${OUT:-$(pwd)/runs/bench-pipeline}"
THREADS=${THREADS:-$(nproc)}
# The arguments checked before anything is written or removed (a bad size emptied the last
# run's pipeline.csv).
[ -x "$BUILD/bin/breccia-solve" ] || { echo "bench_pipeline.sh: BUILD_DIR (argument 1): '$BUILD' has no bin/breccia-solve (expected a built Breccia build folder)" >&2; exit 2; }
BIN="$(cd "$BUILD" && pwd)/bin"
for size in ${SIZES:-demo full}; do
  spec="$CASE/specimen-$size.yaml"; [ "$size" = full ] && spec="$CASE/specimen.yaml"
  [ -f "$spec" ] || { echo "bench_pipeline.sh: SIZES: '$size' has no $spec (expected demo, mid, quick or full)" >&2; exit 2; }
done
mkdir -p "$OUT"
results="$OUT/pipeline.csv"
echo "case,size,threads,particles,steps,mesh_s,place_s,setup_s,step_s,loop_s,post_s,setup_in_steps,post_in_steps,solve_s,header_s,checkpoint_s" > "$results"

now() { date +%s.%N; }
for size in ${SIZES:-demo full}; do
  spec="$CASE/specimen-$size.yaml"; [ "$size" = full ] && spec="$CASE/specimen.yaml"
  if [ ! -f "$spec" ]; then echo "bench_pipeline: $spec not found (SIZES takes demo, mid, quick, full)" >&2; exit 2; fi
  dir="$OUT/$size"; rm -rf "$dir"; mkdir -p "$dir"
  echo "== $size: mesh, place, solve, post (log: $dir/chain.log)"
  t0=$(now)
  "$BIN/breccia-mesh" "$spec" -o "$dir/specimen.msh" --threads 1 > "$dir/chain.log" 2>&1
  t1=$(now)
  "$BIN/breccia-place" "$dir/specimen.msh" -o "$dir/particles.h5" --require-groups concrete,charge_hole >> "$dir/chain.log" 2>&1
  t2=$(now)
  OMP_NUM_THREADS=$THREADS "$BIN/breccia-solve" "$CASE/case.yaml" -o "$dir/run" --threads "$THREADS" --quiet \
    --set "specimen.particles=$dir/particles.h5" ${END_US:+--set "time.end=$END_US us"} >> "$dir/chain.log" 2>&1
  t3=$(now)
  OMP_NUM_THREADS=$THREADS "$BIN/breccia-post" "$dir/run" --particles "$dir/particles.h5" >> "$dir/chain.log" 2>&1
  t4=$(now)
  # Set-up and loop come from the solver's own clocks (summary.json); mesh, place and post are
  # the wall time of each command, start-up and file I/O included.
  "$PYTHON" - "$dir/run/summary.json" "$size" "$THREADS" "$t0" "$t1" "$t2" "$t4" "$t3" >> "$results" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); size, threads = sys.argv[2], sys.argv[3]
t0, t1, t2, t4, t3 = map(float, sys.argv[4:9])
steps = s["steps_this_run"]; step = s["wall_s"] / steps; post = t4 - t3
print(f"concrete-blast,{size},{threads},{s['particles']},{steps},{t1 - t0:.2f},{t2 - t1:.2f},"
      f"{s['setup_wall_s']:.2f},{step:.4f},{s['wall_s']:.1f},{post:.2f},{s['setup_wall_s'] / step:.1f},{post / step:.1f},"
      f"{t3 - t2:.2f},{s.get('results_header_wall_s', 0):.2f},{s.get('final_checkpoint_wall_s', 0):.2f}")
PY
done
echo
column -s, -t < "$results"
echo "(table: $results; load average at the end: $(cut -d' ' -f1-3 /proc/loadavg))"
