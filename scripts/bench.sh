#!/usr/bin/env bash
# Throughput benchmark: bond-updates per second for PMB, LPS and correspondence on a cubic
# lattice with m = 3 (41^3 particles, delta = 3.015 dx), Breccia next to LAMMPS PERI (PMB,
# LPS) in the same run. MODELS="pmb lps correspondence" picks Breccia's models (correspondence:
# float64 only, with its default penalty stabilisation); LAMMPS=0 skips the LAMMPS rows,
# LAMMPS_MODELS=pmb runs LAMMPS's PMB rows only (default "pmb lps").
# bond-updates = particles x mean family size x steps (each bond counted once from each
# end) / wall time of the time loop. Usage: scripts/bench.sh BUILD_DIR [N=41] [STEPS=100]
# MODELS may also name pmb-softening and lps-softening: the same lattice with
# tensile_strength (softening bonds; every bond below its onset, as most bonds of a fracture
# run are), to cost the softening law against the critical-stretch one.
# Time to solution: each process is run under /usr/bin/time; process_wall_s and process_cpu_s
# (user + sys, all threads and, for mpirun, its ranks) cover the whole run: start-up, set-up
# (Breccia: families, bond coefficients, stable-step estimate; LAMMPS: its run 0, which builds
# the PERI families), the time loop and the final writes. setup_wall_s is Breccia's set-up.
set -euo pipefail
source "$(dirname "$0")/lammps_lattice_input.sh"
BUILD=${1:-build}; N=${2:-41}; STEPS=${3:-100}
PYTHON=${PYTHON:-/usr/bin/python3}  # set by the Makefile; run on its own too (docs/performance.md)
# The arguments checked before anything is written: a bad one emptied the last run's bench.csv.
[[ "$N" =~ ^[1-9][0-9]*$ ]] || { echo "bench.sh: N (argument 2): '$N' (expected a whole number of particles per side >= 1)" >&2; exit 2; }
[[ "$STEPS" =~ ^[1-9][0-9]*$ ]] || { echo "bench.sh: STEPS (argument 3): '$STEPS' (expected a whole number of steps >= 1)" >&2; exit 2; }
[ -x "$BUILD/bin/breccia-solve" ] || { echo "bench.sh: BUILD_DIR (argument 1): '$BUILD' has no bin/breccia-solve (expected a built Breccia build folder)" >&2; exit 2; }
BIN="$(cd "$BUILD" && pwd)/bin"
OUT="${OUT:-$(pwd)/runs/bench}"
mkdir -p "$OUT"
DX=0.0005
L=$(awk -v n="$N" -v dx="$DX" 'BEGIN{printf "%.6g", n*dx}')
THREADS_LIST=${THREADS_LIST:-"1 $(nproc)"}
if [ "${LAMMPS:-1}" != 0 ] && ! command -v lmp >/dev/null 2>&1; then
  echo "bench: installing LAMMPS (Debian package lammps) for the side-by-side comparison"
  SUDO=""; [ "$(id -u)" != 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends lammps >/dev/null
fi
if [ ! -x /usr/bin/time ]; then
  echo "bench: /usr/bin/time not found (Debian package 'time'): it times each whole process" >&2; exit 2
fi
results="$OUT/bench.csv"
# The machine's load during the run (a shared machine: compare CPU seconds there).
echo "start $(date -u +%FT%TZ) loadavg $(cat /proc/loadavg)" > "$OUT/load.txt"
trap 'echo "end $(date -u +%FT%TZ) loadavg $(cat /proc/loadavg)" >> "$OUT/load.txt"' EXIT
echo "code,model,precision,threads,particles,bonds_per_particle,steps,loop_wall_s,bond_updates_per_s,per_core_wall,loop_cpu_s,per_cpu_second,process_wall_s,process_cpu_s,setup_wall_s" > "$results"

# PRECISIONS="float64 float32": model.precision (docs/performance.md, float32 rows).
for model in ${MODELS:-pmb lps correspondence}; do
for prec in ${PRECISIONS:-float64 float32}; do
  # The correspondence kernels exist in double precision only (case_config.cpp refuses float32).
  if [ "$model" = correspondence ] && [ "$prec" != float64 ]; then continue; fi
  type=${model%-softening}; strength=""
  [ "$type" = "$model" ] || strength=", tensile_strength: 1 GPa"
  cat > "$OUT/$model-$prec.yaml" <<YAML
name: bench-$model-$prec
specimen: {lattice: {dimension: 3, box: [0, 0, 0, $L, $L, $L], spacing: $DX}}
model: {type: $type, horizon_factor: 3.015, precision: $prec}
materials: [{name: m, density: 2200, youngs_modulus: 22.35 GPa, poisson_ratio: 0.25, fracture_energy: 1e6$strength}]
initial: [{type: radial_velocity, center: [0, 0, 0], strain_rate: 10}]
time: {steps: $STEPS}
output: {every: 1000000, history_every: 1000000, results: false}
YAML
  for t in $THREADS_LIST; do
    OMP_NUM_THREADS=$t /usr/bin/time -f "%e %U %S" -o "$OUT/time-breccia-$model-$prec-$t" "$BIN/breccia-solve" "$OUT/$model-$prec.yaml" -o "$OUT/breccia-$model-$prec-$t" --threads "$t" --quiet --backend cpu
    $PYTHON - "$OUT/breccia-$model-$prec-$t/summary.json" "$model" "$t" "$prec" "$OUT/time-breccia-$model-$prec-$t" >> "$results" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); t = int(sys.argv[3])
wall, user, sys_s = map(float, open(sys.argv[5]).read().split()[-3:])
print(f"breccia,{sys.argv[2]},{sys.argv[4]},{t},{s['particles']},{s['mean_family_size']:.1f},{s['steps_this_run']},{s['wall_s']:.3f},{s['bond_updates_per_s']:.4g},{s['bond_updates_per_s']/t:.4g},{s['loop_cpu_s']:.3f},{s['bond_updates_per_cpu_s']:.4g},{wall:.2f},{user + sys_s:.2f},{s['setup_wall_s']:.2f}")
PY
  done
done
done

if [ "${LAMMPS:-1}" = 0 ]; then
  echo; column -s, -t < "$results"; echo "(table: $results; LAMMPS skipped)"; exit 0
fi
# LAMMPS PERI on the same lattice (E 22.35 GPa, nu 1/4: K = 14.9 GPa, G = 8.94 GPa).
# LAMMPS families: lattice points within delta (FixPeriNeigh), counted here exactly.
BONDS=$($PYTHON - "$N" <<'PY'
import numpy as np, sys
n = int(sys.argv[1]); r = 3.015
off = np.array([(a, b, c) for a in range(-4, 5) for b in range(-4, 5) for c in range(-4, 5)
                if 0 < a*a + b*b + c*c <= r*r])
idx = np.arange(n)
total = 0
for a, b, c in off:  # pairs along each offset inside the n^3 block
    total += max(0, n - abs(a)) * max(0, n - abs(b)) * max(0, n - abs(c))
print(f"{total / n**3:.1f}")
PY
)
for model in ${LAMMPS_MODELS:-pmb lps}; do
  write_lammps_lattice_input "$OUT/lammps-$model.in" "$model" "$N" "$DX" "$STEPS"
  for t in $THREADS_LIST; do
    if ( cd "$OUT" && /usr/bin/time -f "%e %U %S" -o "time-lammps-$model-$t" mpirun --allow-run-as-root --oversubscribe -np "$t" lmp -in "lammps-$model.in" -log "lammps-$model-$t.log" -screen none ) >/dev/null 2>&1; then
      loop=$(grep "^Loop time" "$OUT/lammps-$model-$t.log" | tail -1 | awk '{print $4}')
      atoms=$((N*N*N))
      rate=$(awk -v a=$atoms -v b=$BONDS -v s=$STEPS -v l=$loop 'BEGIN{printf "%.4g", a*b*s/l}')
      per=$(awk -v r=$rate -v t=$t 'BEGIN{printf "%.4g", r/t}')
      # LAMMPS reports the CPU share of the loop: "NN% CPU use with P MPI tasks".
      pct=$(grep "CPU use with" "$OUT/lammps-$model-$t.log" | tail -1 | awk '{print $1}' | tr -d '%')
      cpu=$(awk -v l=$loop -v p=$pct -v t=$t 'BEGIN{printf "%.4g", l*p/100*t}')
      percpu=$(awk -v a=$atoms -v b=$BONDS -v s=$STEPS -v c=$cpu 'BEGIN{printf "%.4g", a*b*s/c}')
      proc=$(awk '{w=$1; c=$2+$3} END{printf "%.2f,%.2f", w, c}' "$OUT/time-lammps-$model-$t")
      echo "lammps,$model,float64,$t,$atoms,$BONDS,$STEPS,$loop,$rate,$per,$cpu,$percpu,$proc," >> "$results"
    else
      echo "lammps,$model,float64,$t,,,,failed (see $OUT/lammps-$model-$t.log),," >> "$results"
      lammps_failed=1
    fi
  done
done
echo
column -s, -t < "$results"
echo "(table: $results)"
# A failed LAMMPS row leaves the comparison the bench exists for incomplete: the table is
# written, and the run says so with a non-zero exit.
if [ "${lammps_failed:-0}" = 1 ]; then echo "bench.sh: a LAMMPS run failed (rows marked failed above)" >&2; exit 1; fi
