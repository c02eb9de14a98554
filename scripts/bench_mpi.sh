#!/usr/bin/env bash
# Strong scaling of a distributed run (docs/parallel.md, docs/performance.md): the 41^3
# lattice of scripts/bench.sh (m = 3, PMB and LPS) on 1 and 2 MPI ranks of one thread each,
# beside one process on 1 and 2 threads and LAMMPS PERI on 1 and 2 ranks, in the same run.
# Time to solution is the whole command's wall time (set-up, loop, files); the loop's own
# wall time is what the speed-up is measured on.
# Usage: scripts/bench_mpi.sh BUILD_DIR [N=41] [STEPS=200]   (OUT=runs/bench-mpi)
set -euo pipefail
source "$(dirname "$0")/lammps_lattice_input.sh"
BUILD=${1:-build}; N=${2:-41}; STEPS=${3:-200}
[[ "$N" =~ ^[1-9][0-9]*$ ]] || { echo "bench_mpi.sh: N (argument 2): '$N' (expected a whole number of particles per side >= 1)" >&2; exit 2; }
[[ "$STEPS" =~ ^[1-9][0-9]*$ ]] || { echo "bench_mpi.sh: STEPS (argument 3): '$STEPS' (expected a whole number of steps >= 1)" >&2; exit 2; }
[ -x "$BUILD/bin/breccia-solve" ] || { echo "bench_mpi.sh: BUILD_DIR (argument 1): '$BUILD' has no bin/breccia-solve (expected a built Breccia build folder)" >&2; exit 2; }
BIN="$(cd "$BUILD" && pwd)/bin"
OUT="${OUT:-$(pwd)/runs/bench-mpi}"
PYTHON=${PYTHON:-/usr/bin/python3}
mkdir -p "$OUT"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
DX=0.0005
L=$(awk -v n="$N" -v dx="$DX" 'BEGIN{printf "%.6g", n*dx}')
results="$OUT/scaling.csv"
echo "code,model,ranks,threads,particles,steps,setup_s,loop_wall_s,total_wall_s,bond_updates_per_s" > "$results"
now() { date +%s.%N; }

for model in pmb lps; do
  cat > "$OUT/$model.yaml" <<YAML
name: scaling-$model
specimen: {lattice: {dimension: 3, box: [0, 0, 0, $L, $L, $L], spacing: $DX}}
model: {type: $model, horizon_factor: 3.015}
materials: [{name: m, density: 2200, youngs_modulus: 22.35 GPa, poisson_ratio: 0.25, fracture_energy: 1e6}]
initial: [{type: radial_velocity, center: [0, 0, 0], strain_rate: 10}]
time: {steps: $STEPS}
output: {every: 1000000, history_every: 1000000, results: false}
YAML
  for config in "1 1" "1 2" "2 1"; do
    set -- $config; ranks=$1; threads=$2
    run="$OUT/breccia-$model-np$ranks-t$threads"
    launch=""; [ "$ranks" -gt 1 ] && launch="mpirun --oversubscribe -np $ranks"
    t0=$(now)
    OMP_NUM_THREADS=$threads $launch "$BIN/breccia-solve" "$OUT/$model.yaml" -o "$run" --threads "$threads" --quiet --backend cpu
    t1=$(now)
    $PYTHON - "$run/summary.json" "$model" "$ranks" "$threads" "$(awk -v a=$t0 -v b=$t1 'BEGIN{print b-a}')" >> "$results" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(f"breccia,{sys.argv[2]},{sys.argv[3]},{sys.argv[4]},{s['particles']},{s['steps_this_run']},{s['setup_wall_s']:.2f},"
      f"{s['wall_s']:.3f},{float(sys.argv[5]):.2f},{s['bond_updates_per_s']:.4g}")
PY
  done
  write_lammps_lattice_input "$OUT/lammps-$model.in" "$model" "$N" "$DX" "$STEPS"
  if command -v lmp >/dev/null 2>&1; then
    for ranks in 1 2; do
      t0=$(now)
      if ( cd "$OUT" && OMP_NUM_THREADS=1 mpirun --oversubscribe -np "$ranks" lmp -in "lammps-$model.in" -log "lammps-$model-$ranks.log" -screen none ) >/dev/null 2>&1; then
        t1=$(now)
        loop=$(grep "^Loop time" "$OUT/lammps-$model-$ranks.log" | tail -1 | awk '{print $4}')
        echo "lammps,$model,$ranks,1,$((N*N*N)),$STEPS,,$loop,$(awk -v a=$t0 -v b=$t1 'BEGIN{printf "%.2f", b-a}')," >> "$results"
      else
        echo "lammps,$model,$ranks,1,,,,failed (see $OUT/lammps-$model-$ranks.log),," >> "$results"
        lammps_failed=1
      fi
    done
  else
    echo "bench_mpi: lmp not found: no LAMMPS rows (scripts/bench.sh installs the Debian package lammps)" >&2
    lammps_missing=1
  fi
done
# Speed-ups of the loop and of the whole run from 1 to 2 ranks, per code and model.
$PYTHON - "$results" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
def find(code, model, ranks, threads):
    for r in rows:
        if (r["code"], r["model"], r["ranks"], r["threads"]) == (code, model, str(ranks), str(threads)) and r["loop_wall_s"]:
            try: return float(r["loop_wall_s"]), float(r["total_wall_s"])
            except ValueError: return None
for code in ("breccia", "lammps"):
    for model in ("pmb", "lps"):
        one, two = find(code, model, 1, 1), find(code, model, 2, 1)
        if one and two:
            print(f"{code} {model}: 1 -> 2 ranks, loop speed-up {one[0] / two[0]:.2f}x, whole run {one[1] / two[1]:.2f}x")
    for model in ("pmb", "lps"):
        b, l = find("breccia", model, 2, 1), find("lammps", model, 2, 1)
        if code == "breccia" and b and l:
            print(f"{model} on 2 ranks: Breccia's whole run {l[1] / b[1]:.2f}x faster than LAMMPS's")
PY
echo; column -s, -t < "$results"; echo "(table: $results)"
# The comparison is what this bench is for: a LAMMPS run that failed or a missing lmp is a
# non-zero exit (the table is written first).
if [ "${lammps_failed:-0}" = 1 ] || [ "${lammps_missing:-0}" = 1 ]; then
  echo "bench_mpi: the LAMMPS comparison is incomplete (see above)" >&2; exit 1
fi
