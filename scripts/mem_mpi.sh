#!/usr/bin/env bash
# Peak memory per rank of a distributed run (docs/parallel.md, Memory): a box lattice (PMB by default) of
# N^3 particles (m = 3.015) run for a few steps on 1, 2 and 4 ranks of one thread each; each
# rank's peak resident set (VmHWM, GNU time's %M) in MB, beside summary.json's figures, and each
# rank's resident set at the end of the time loop (summary.json's loop_resident_mb: VmRSS after
# the last step, before the final outputs; the peak is the set-up's).
# Usage: scripts/mem_mpi.sh BUILD_DIR [N=30] [RANKS="1 2 4"]   (OUT=runs/mem-mpi)
# MODEL: the model keys (default "type: pmb"; e.g. "type: lps", "type: pmb, precision: float32").
# TIME: the time keys (default "steps: 5"; e.g. "integrator: adr, adr_tolerance: 1": a dozen iterations).
# GAS=SIZE: instead of the lattice, a gas load (loads[].type: gas): the gas tests' disc (40 mm
#   radius, 5 mm charge hole, plane strain) meshed at SIZE throughout (e.g. GAS="0.5 mm":
#   46,062 particles), LPS with the dual horizon, 20 MPa of gas behind a pre-crack; N unused.
# RESULTS=1: results.h5 written too (its first and last output groups: the bond list, the
#   broken bits); default none.
# RESTART=1: each run is then continued from its checkpoint.h5 on the same ranks for 5 steps
#   more (--restart, --steps): a second row per rank count, "R restart", with that run's peaks.
# CASE=FILE: instead of the lattice or the disc, a case file as it is, with CASE_ARGS (options
#   added to every run, split at spaces), e.g. the full concrete case for one step:
#   CASE=cases/concrete-blast/case.yaml CASE_ARGS="--set specimen.particles=$PWD/runs/full/particles.h5 --steps 1"
set -euo pipefail
BUILD=${1:-build}; N=${2:-30}; RANKS=${3:-"1 2 4"}; MODEL=${MODEL:-"type: pmb"}; TIME=${TIME:-"steps: 5"}
WRITE_RESULTS=false; [ "${RESULTS:-0}" = 1 ] && WRITE_RESULTS=true
BIN="$(cd "$BUILD" && pwd)/bin"
OUT="${OUT:-$(pwd)/runs/mem-mpi}"
mkdir -p "$OUT"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
CASE_FILE="$OUT/case.yaml"; read -r -a CASE_EXTRA <<< "${CASE_ARGS:-}"
if [ -n "${CASE:-}" ]; then
  CASE_FILE="$(cd "$(dirname "$CASE")" && pwd)/$(basename "$CASE")"
elif [ -n "${GAS:-}" ]; then
  cat > "$OUT/specimen.yaml" <<YAML
dimension: 2
thickness: 10 mm
body: {shape: disc, name: rock, radius: 40 mm}
holes: [{name: charge_hole, centre: [0, 0], radius: 5 mm}]
mesh: {size: $GAS}
YAML
  "$BIN/breccia-mesh" "$OUT/specimen.yaml" -o "$OUT/specimen.msh" --quiet > /dev/null
  "$BIN/breccia-place" "$OUT/specimen.msh" -o "$OUT/particles.h5" --thickness 10mm > /dev/null
  cat > "$OUT/case.yaml" <<YAML
name: memory-per-rank-gas
specimen: {particles: $OUT/particles.h5}
model: {type: lps, planar: plane_strain, horizon_factor: 3.015, variable_horizon: true}
materials: [{name: rock, density: 2000, youngs_modulus: 1 GPa, poisson_ratio: 0.25, fracture_energy: 20}]
precracks: [{type: segment, from: [4 mm, 0.01 mm], to: [15 mm, 0.01 mm]}]
loads:
  - {type: gas, surface: charge_hole, history: {type: constant, value: 20 MPa}, gamma_high: 3, gamma_low: 1.4,
     switch_pressure: 18 MPa, ambient_pressure: 0, front_speed: 500 m/s, gas_density: 1000 kg/m3}
time: {$TIME}
output: {every: 1000000, history_every: 1000000, results: $WRITE_RESULTS}
YAML
else
DX=0.0005
L=$(awk -v n="$N" -v dx="$DX" 'BEGIN{printf "%.6g", n*dx}')
cat > "$OUT/case.yaml" <<YAML
name: memory-per-rank
specimen: {lattice: {dimension: 3, box: [0, 0, 0, $L, $L, $L], spacing: $DX}}
model: {$MODEL, horizon_factor: 3.015}
materials: [{name: m, density: 2200, youngs_modulus: 22.35 GPa, poisson_ratio: 0.25, fracture_energy: 1e6}]
initial: [{type: radial_velocity, center: [0, 0, 0], strain_rate: 10}]
time: {$TIME}
output: {every: 1000000, history_every: 1000000, results: $WRITE_RESULTS}
YAML
fi
echo "ranks,particles,bond_entries,peak_rss_mb_per_rank (rank 0 first),peak_rss_mb_max,peak_rss_mb_sum,loop_rss_mb_per_rank,loop_rss_mb_max,loop_rss_mb_sum"
# One run on $1 ranks into $2, each rank's peak into $2/rss$3.RANK, then its row ($4: its label).
measure() {
  local ranks=$1 run=$2 tag=$3 label=$4; shift 4
  # One file per rank: GNU time writes the rank's own peak when it exits.
  OMP_NUM_THREADS=1 mpirun --oversubscribe -np "$ranks" bash -c \
    '/usr/bin/time -f %M -o "$0/rss$1.$OMPI_COMM_WORLD_RANK" "${@:2}"' \
    "$run" "$tag" "$BIN/breccia-solve" "$CASE_FILE" -o "$run" --threads 1 --quiet --backend cpu ${CASE_EXTRA[@]+"${CASE_EXTRA[@]}"} "$@"
  /usr/bin/python3 - "$run" "$ranks" "$tag" "$label" <<'PY'
import json, sys
run, ranks, tag, label = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
s = json.load(open(f"{run}/summary.json"))
mb = [int(open(f"{run}/rss{tag}.{r}").read().split()[-1]) / 1024 for r in range(ranks)]
loop = s.get("loop_resident_mb", [])
tail = f",{' '.join(f'{m:.0f}' for m in loop)},{max(loop):.0f},{sum(loop):.0f}" if loop else ",,,"
print(f"{label},{s['particles']},{s['bonds']},{' '.join(f'{m:.0f}' for m in mb)},{max(mb):.0f},{sum(mb):.0f}{tail}")
PY
}
for ranks in $RANKS; do
  run="$OUT/np$ranks"
  rm -rf "$run"; mkdir -p "$run"
  measure "$ranks" "$run" "" "$ranks"
  if [ "${RESTART:-0}" = 1 ]; then
    step=$(/usr/bin/python3 -c 'import h5py, sys; print(int(h5py.File(sys.argv[1], "r").attrs["step"]))' "$run/checkpoint.h5")
    measure "$ranks" "$run" "-restart" "$ranks restart" --restart "$run/checkpoint.h5" --steps $((step + 5))
  fi
done
