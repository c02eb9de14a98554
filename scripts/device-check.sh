#!/usr/bin/env bash
# The GPU session's one command (docs/cuda.md, "How to verify on a GPU"): CPU/GPU agreement
# tests of the PD and MPS launchers, then the GPU figures docs/performance.md and
# cases/mps-harmonics need (PD PMB/LPS bond-updates/s, MPS harmonics at 0.125 mm CPU vs GPU).
#
#   1. Here, on the CPU machine (no device time):
#        scripts/device-check.sh prepare
#      builds breccia-solve, test_solver_cuda and test_mps_cuda for sm_90 in build-device/ and
#      packs them with the shared libraries they load into build-device/kit (~25 MB). The
#      device machine has nvcc but no HDF5, yaml-cpp or GoogleTest headers (nothing can be
#      installed there), so the binaries travel instead of being built there.
#        BRECCIA_DEVICE_DRY=1 scripts/device-check.sh
#      rehearses everything but the GPU runs here (small sizes, OUT=/tmp/device-check-dry).
#   2. On the device machine, through the device tool's run:
#        command: bash scripts/device-check.sh     carry: ["build-device/kit"]     timeout_s: 540
#      Everything it measures lands in $OUT (results.json, summary.md, logs), written as it
#      goes, so a run cut short still returns what it finished.
#
# ONLY=tests,mps,taylor,pd,atlas runs only the named sections (the device's 15 minutes need two
# calls: e.g. ONLY=tests,pd then ONLY=mps,taylor,atlas).
# Environment: OUT (results folder), BRECCIA_DEVICE_DRY=1 (no GPU runs), PD_N (lattice edge,
# default 81: 531k particles, 6.5e7 bond entries), PD_GPU_STEPS (500), PD_CPU_STEPS (20),
# MPS_SPACING (0.125 mm), SANITIZER=0 to skip compute-sanitizer, BUDGET_S (480: no new check
# starts after this many seconds).
set -uo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
KIT="$ROOT/build-device/kit"

if [ "${1:-}" = prepare ]; then
  set -e
  BUILD="$ROOT/build-device"
  LAUNCHER=()
  command -v ccache >/dev/null && LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_CUDA_COMPILER_LAUNCHER=ccache)
  cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DBRECCIA_STAGES=solver -DBRECCIA_CUDA=ON \
    -DCMAKE_CUDA_ARCHITECTURES=90 "${LAUNCHER[@]}" >"$BUILD.configure.log" 2>&1 || { cat "$BUILD.configure.log"; exit 1; }
  nice -n 10 cmake --build "$BUILD" -j"${JOBS:-2}" --target breccia-solve breccia-atlas test_solver_cuda test_mps_cuda test_mps_solid_cuda test_atlas_backends
  rm -rf "$KIT"
  mkdir -p "$KIT/bin" "$KIT/lib" "$KIT/runtime" "$KIT/glibc" "$KIT/cases"
  cp "$BUILD/bin/breccia-solve" "$BUILD/bin/breccia-atlas" "$BUILD/bin/test_solver_cuda" "$BUILD/bin/test_mps_cuda" \
    "$BUILD/bin/test_mps_solid_cuda" "$BUILD/bin/test_atlas_backends" "$KIT/bin/"
  # Libraries by layer: lib/ (HDF5, yaml-cpp and what they load) always; runtime/ (the GCC
  # runtime) only if the device's own is missing or older; glibc/ with its loader as a last resort.
  for exe in "$KIT"/bin/*; do ldd "$exe"; done | awk '$3 ~ /^\// {print $3} $1 ~ /^\/.*ld-linux/ {print $1}' | sort -u |
    while read -r lib; do
      name=$(basename "$lib")
      case "$name" in
        ld-linux*|libc.so*|libm.so*|libpthread.so*|libdl.so*|librt.so*|libresolv.so*|libutil.so*) cp -L "$lib" "$KIT/glibc/" ;;
        libstdc++.so*|libgcc_s.so*|libgomp.so*) cp -L "$lib" "$KIT/runtime/" ;;
        *) cp -L "$lib" "$KIT/lib/" ;;
      esac
    done
  cp "$ROOT/cases/mps-harmonics/case.yaml" "$KIT/cases/mps-harmonics.yaml"
  cp "$ROOT/cases/mps-taylor-bar/case.yaml" "$KIT/cases/mps-taylor-bar.yaml"
  {
    echo "built: $(date -u +%FT%TZ) on $(hostname)"
    echo "commit: $(git -C "$ROOT" rev-parse HEAD 2>/dev/null) (+ uncommitted changes: $(git -C "$ROOT" status --porcelain 2>/dev/null | wc -l) paths)"
    /usr/local/cuda/bin/nvcc --version 2>/dev/null | tail -2
  } >"$KIT/MANIFEST"
  du -sh "$KIT"
  echo "kit ready: carry [\"build-device/kit\"] and run 'bash scripts/device-check.sh' on the device"
  exit 0
fi

DRY=${BRECCIA_DEVICE_DRY:-0}
if [ "$DRY" = 1 ]; then OUT=${OUT:-/tmp/device-check-dry}; else OUT=${OUT:-$ROOT/runs/device-check}; fi
mkdir -p "$OUT"
WORK=$(mktemp -d /tmp/device-check.XXXXXX)
exec > >(tee -a "$OUT/device-check.log") 2>&1
START=$(date +%s)
step() { echo; echo "== [$(($(date +%s) - START)) s] $*"; }
# A check starts only before BUDGET_S (default 480 s of the device tool's 540 s timeout) and
# is cut off by BUDGET_S + 40 s, so the results files are always written.
limit() { local left=$((${BUDGET_S:-480} + 40 - ($(date +%s) - START))); echo $((left < $1 ? (left > 10 ? left : 10) : $1)); }
in_budget() { [ $(($(date +%s) - START)) -lt "${BUDGET_S:-480}" ] || { echo "skipped: $1 (budget ${BUDGET_S:-480} s spent)"; result "skipped_$1" 1; false; }; }
RESULTS="$OUT/results.txt"  # key=value as measured; results.json and summary.md are made from it on exit
: >"$RESULTS"
result() { echo "$1=$2" >>"$RESULTS"; }
THREADS=$(nproc)
PYTHON=${PYTHON:-python3}  # the device's python3 has numpy; here /usr/bin/python3 does
"$PYTHON" -c "import numpy" 2>/dev/null || PYTHON=/usr/bin/python3
if [ "$DRY" = 1 ]; then
  PD_N=${PD_N:-21}; PD_GPU_STEPS=${PD_GPU_STEPS:-20}; PD_CPU_STEPS=${PD_CPU_STEPS:-10}
  MPS_SPACING=${MPS_SPACING:-0.25}; MPS_END="3 us"
else
  PD_N=${PD_N:-81}; PD_GPU_STEPS=${PD_GPU_STEPS:-500}; PD_CPU_STEPS=${PD_CPU_STEPS:-20}
  MPS_SPACING=${MPS_SPACING:-0.125}; MPS_END="30 us"
fi
GPU_BACKEND=cuda
[ "$DRY" = 1 ] && GPU_BACKEND=cpu  # the rehearsal runs the "GPU" legs on the CPU to test the plumbing

finish() {
  step "results"
  "$PYTHON" - "$RESULTS" "$OUT" <<'PY'
import json, sys
res = {}
for line in open(sys.argv[1]):
    if "=" in line:
        k, v = line.rstrip("\n").split("=", 1)
        try: v = float(v) if ("." in v or "e" in v.lower()) else int(v)
        except ValueError: pass
        res[k] = v
json.dump(res, open(sys.argv[2] + "/results.json", "w"), indent=1, sort_keys=True)
def g(k, f="{}"):
    return f.format(res[k]) if k in res else "-"
rows = [
  "# device-check results" + (" (DRY: no GPU runs)" if res.get("dry") == 1 else ""),
  "", f"device: {g('device')}; binaries: {g('binaries')}; elapsed {g('elapsed_s')} s", "",
  "| check | result |", "|---|---|",
  f"| test_mps_cuda | {g('test_mps_cuda')} |", f"| test_mps_solid_cuda | {g('test_mps_solid_cuda')} |",
  f"| test_solver_cuda | {g('test_solver_cuda')} |", f"| test_atlas_backends | {g('test_atlas_backends')} |",
  f"| atlas GPU rows (wave speed bar, Kalthoff-Winkler; lattice, m = 3) | {g('atlas_rows')} rows in atlas_gpu.csv, rc {g('atlas_rc')} |",
  f"| compute-sanitizer memcheck (MPS) | {g('sanitizer_mps')} |",
  f"| MPS harmonics history GPU vs CPU (max rel. diff) | {g('mps_history_max_rel_diff', '{:.3e}')} |",
  "", "| run | particles | steps | loop wall (s) | rate |", "|---|---|---|---|---|",
]
for leg in ("gpu", "cpu"):
    k = f"mps_{leg}"
    rows.append(f"| MPS harmonics {g('mps_spacing_mm')} mm, {leg} ({g(k + '_backend')}) | {g(k + '_particles')} | "
                f"{g(k + '_steps')} | {g(k + '_loop_s')} | {g(k + '_particle_steps_per_s', '{:.3g}')} particle-steps/s |")
rows.append(f"| MPS Taylor bar {g('taylor_across')} across, gpu ({g('taylor_backend')}) | {g('taylor_particles')} | "
            f"{g('taylor_steps')} (max {g('taylor_max_substeps')} substeps) | {g('taylor_loop_s')} | "
            f"{g('taylor_particle_steps_per_s', '{:.3g}')} particle-steps/s; length {g('taylor_length_mm', '{:.2f}')} mm, "
            f"face radius {g('taylor_radius_mm', '{:.2f}')} mm |")
for model in ("pmb", "lps", "correspondence", "pmb32", "lps32"):
    for leg in ("gpu", "cpu"):
        k = f"pd_{model}_{leg}"
        rows.append(f"| PD {model} lattice {g('pd_n')}^3, {leg} ({g(k + '_backend')}, {g(k + '_threads')} threads) | "
                    f"{g(k + '_particles')} | {g(k + '_steps')} | {g(k + '_wall_s')} | {g(k + '_bond_updates_per_s', '{:.3g}')} bond-updates/s |")
open(sys.argv[2] + "/summary.md", "w").write("\n".join(rows) + "\n")
print("\n".join(rows))
PY
  # Logs, decks, summaries and histories; no results.h5 (tens of MB at 0.125 mm, over the 16 MB a file may bring back).
  tar -czf "$OUT/runs.tar.gz" --exclude='*.h5' -C "$WORK" . 2>/dev/null
  rm -rf "$WORK"
}
trap 'result elapsed_s $(($(date +%s) - START)); finish' EXIT
result dry "$DRY"

step "machine"
uname -a; grep PRETTY_NAME /etc/os-release; echo "cores: $THREADS"
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm --format=csv
command -v nvcc >/dev/null && nvcc --version | tail -1
[ -f "$KIT/MANIFEST" ] && cat "$KIT/MANIFEST"

step "binaries"
# Prefer the carried kit (no build: ~0 s); try the device's own GCC runtime first, then the
# kit's, then the kit's glibc and loader. Building here would need HDF5, yaml-cpp and
# GoogleTest (and, for the top-level CMakeLists, gmsh, CGAL and VTK), which the image lacks.
MODE=none
ENVP=() LOADP=()  # a kit binary runs as: "${ENVP[@]}" "${LOADP[@]}" EXE ARGS
use_mode() {
  MODE=$1 ENVP=() LOADP=()
  case "$1" in
    libs) ENVP=(env LD_LIBRARY_PATH="$KIT/lib") ;;
    runtime) ENVP=(env LD_LIBRARY_PATH="$KIT/lib:$KIT/runtime") ;;
    loader) LOADP=("$KIT/glibc/ld-linux-x86-64.so.2" --library-path "$KIT/lib:$KIT/runtime:$KIT/glibc") ;;
  esac
}
run_bin() { "${ENVP[@]}" "${LOADP[@]}" "$@"; }
if [ -x "$KIT/bin/breccia-solve" ]; then
  for m in libs runtime loader; do
    use_mode $m
    if run_bin "$KIT/bin/breccia-solve" --help >/dev/null 2>&1 && run_bin "$KIT/bin/test_mps_cuda" --gtest_list_tests >/dev/null 2>&1; then break; fi
    use_mode none
  done
  BIN="$KIT/bin"
fi
# What a build on this machine would lack (recorded for the next session's plan).
missing=""
for h in /usr/include/hdf5/serial/hdf5.h:hdf5 /usr/include/yaml-cpp/yaml.h:yaml-cpp /usr/include/gtest/gtest.h:googletest \
         /usr/include/eigen3:eigen /usr/include/gmsh.h:gmsh /usr/include/CGAL:cgal /usr/include/vtk-9.1:vtk; do
  [ -e "${h%%:*}" ] || missing="$missing ${h##*:}"
done
command -v nvcc >/dev/null || missing="$missing nvcc"
result build_deps_missing "${missing:- none}"
echo "build dependencies missing here:${missing:- none}"
if [ "$MODE" = none ]; then
  if [ -z "$missing" ] && command -v nvcc >/dev/null; then
    echo "no runnable kit: building the solver stage here with -j$THREADS"
    cmake -S "$ROOT" -B /tmp/breccia-build -DCMAKE_BUILD_TYPE=Release -DBRECCIA_STAGES=solver -DBRECCIA_CUDA=ON \
      -DCMAKE_CUDA_ARCHITECTURES=90 >/tmp/breccia-configure.log 2>&1 &&
      cmake --build /tmp/breccia-build -j"$THREADS" --target breccia-solve breccia-atlas test_solver_cuda test_mps_cuda test_mps_solid_cuda test_atlas_backends >/tmp/breccia-build.log 2>&1 &&
      use_mode native && BIN=/tmp/breccia-build/bin
    [ "$MODE" = none ] && tail -30 /tmp/breccia-configure.log /tmp/breccia-build.log
  else
    echo "no runnable kit and no local build possible (missing:${missing:- nvcc})"
  fi
fi
result binaries "$MODE"
if [ "$MODE" = none ]; then
  echo "FAILED: run 'scripts/device-check.sh prepare' on the CPU machine and carry build-device/kit"
  exit 1
fi
echo "binaries: $BIN (library mode: $MODE)"
DEVICE=$(command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name --format=csv,noheader | head -1)
result device "${DEVICE:-none}"

# gtest: PASSED/FAILED/SKIPPED counts into the results, the XML report into $OUT.
run_tests() {  # run_tests NAME TIMEOUT [gtest args]
  local name=$1 limit=$2; shift 2
  step "$name"
  BRECCIA_CUDA_SYNC=1 timeout "$(limit "$limit")" "${ENVP[@]}" "${LOADP[@]}" "$BIN/$name" --gtest_output=xml:"$OUT/$name.xml" "$@" \
    >"$WORK/$name.log" 2>&1
  local rc=$?
  grep -E "^\[ +(OK|FAILED|SKIPPED) +\]|\[(mps )?cuda\]|Failure|error" "$WORK/$name.log" | head -80
  local passed failed skipped
  passed=$(grep -c "^\[       OK \]" "$WORK/$name.log"); failed=$(grep -c "^\[  FAILED  \] [A-Za-z0-9_]*\.[A-Za-z0-9_]* (" "$WORK/$name.log")
  skipped=$(grep -c "^\[  SKIPPED \] [A-Za-z0-9_]*\.[A-Za-z0-9_]* (" "$WORK/$name.log")
  result "$name" "rc $rc: $passed passed, $failed failed, $skipped skipped"
  echo "$name: rc $rc: $passed passed, $failed failed, $skipped skipped"
}
wanted() { [ -z "${ONLY:-}" ] || [[ ",$ONLY," == *",$1,"* ]]; }
if wanted tests; then
  run_tests test_mps_cuda 180
  in_budget test_mps_solid_cuda && run_tests test_mps_solid_cuda 150
  in_budget test_solver_cuda && run_tests test_solver_cuda 240
  in_budget test_atlas_backends && run_tests test_atlas_backends 60
fi

# MPS: the harmonics case at one spacing, GPU then CPU on every core; histories compared.
step "MPS harmonics at $MPS_SPACING mm"
sed -e "s/spacing: 0.25 mm/spacing: $MPS_SPACING mm/" -e "s/time: {end: 30 us/time: {end: $MPS_END/" \
  "$KIT/cases/mps-harmonics.yaml" >"$WORK/harmonics.yaml" 2>/dev/null ||
  sed -e "s/spacing: 0.25 mm/spacing: $MPS_SPACING mm/" -e "s/time: {end: 30 us/time: {end: $MPS_END/" \
    "$ROOT/cases/mps-harmonics/case.yaml" >"$WORK/harmonics.yaml"
result mps_spacing_mm "$MPS_SPACING"
mps_leg() {  # mps_leg gpu|cpu BACKEND
  local leg=$1 backend=$2 dir="$WORK/mps_$1"
  timeout "$(limit 240)" "${ENVP[@]}" "${LOADP[@]}" "$BIN/breccia-solve" "$WORK/harmonics.yaml" -o "$dir" --backend "$backend" \
    --threads "$THREADS" >"$WORK/mps_$leg.log" 2>&1
  local rc=$?
  grep -E "^mps:|error|warning" "$WORK/mps_$leg.log"
  result "mps_${leg}_rc" "$rc"
  [ -f "$dir/summary.json" ] && "$PYTHON" - "$dir/summary.json" "mps_$leg" >>"$RESULTS" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); k = sys.argv[2]
for f in ("particles", "steps", "wall_time_s", "particle_steps_per_s", "max_slipping_fraction"):
    print(f"{k}_{f}={s[f]}")
print(f"{k}_loop_s={s['step_loop_s']}")
print(f"{k}_backend={s.get('backend', '?')}")
PY
}
wanted mps && in_budget mps_gpu && mps_leg gpu "$GPU_BACKEND"
wanted mps && in_budget mps_cpu && mps_leg cpu cpu
if [ -f "$WORK/mps_gpu/history.csv" ] && [ -f "$WORK/mps_cpu/history.csv" ]; then
  "$PYTHON" - "$WORK/mps_gpu/history.csv" "$WORK/mps_cpu/history.csv" >>"$RESULTS" <<'PY'
import sys
import numpy as np
g = np.loadtxt(sys.argv[1], delimiter=",", skiprows=1, ndmin=2)
c = np.loadtxt(sys.argv[2], delimiter=",", skiprows=1, ndmin=2)
if g.shape != c.shape:
    print(f"mps_history_max_rel_diff=shape {g.shape} vs {c.shape}")
else:
    scale = np.maximum(np.abs(c).max(axis=0), 1e-300)  # per column: probes pass through zero
    print(f"mps_history_max_rel_diff={float((np.abs(g - c) / scale).max()):.6e}")
PY
  grep mps_history "$RESULTS"
fi

# MPS stress formulation: the Taylor bar at TAYLOR_ACROSS particles across (default 32: about
# 130k particles, finer than any CPU run), GPU only; length and face radius at 80 us as
# cases/mps-taylor-bar/report.py measures them (where h5py is present).
TAYLOR_ACROSS=${TAYLOR_ACROSS:-32}
[ "$DRY" = 1 ] && TAYLOR_ACROSS=4
if wanted taylor && in_budget taylor; then
  step "MPS Taylor bar, $TAYLOR_ACROSS across"
  TAYLOR_CASE="$KIT/cases/mps-taylor-bar.yaml"
  [ -f "$TAYLOR_CASE" ] || TAYLOR_CASE="$ROOT/cases/mps-taylor-bar/case.yaml"
  read -r H < <("$PYTHON" -c "print(repr(6.4e-3 / $TAYLOR_ACROSS))")
  sed -e "s/spacing: 0.8 mm .*/spacing: $H/" -e "s/every: 100000 .*/every: 1000000/" -e "s/end: 80 us/end: ${TAYLOR_END:-80 us}/" \
    "$TAYLOR_CASE" >"$WORK/taylor.yaml"
  result taylor_across "$TAYLOR_ACROSS"
  timeout "$(limit 200)" "${ENVP[@]}" "${LOADP[@]}" "$BIN/breccia-solve" "$WORK/taylor.yaml" -o "$WORK/taylor" \
    --backend "$GPU_BACKEND" --threads "$THREADS" >"$WORK/taylor.log" 2>&1
  result taylor_rc "$?"
  grep -E "^mps|error" "$WORK/taylor.log" | tail -4
  [ -f "$WORK/taylor/summary.json" ] && "$PYTHON" - "$WORK/taylor" "$H" >>"$RESULTS" <<'PY'
import json, sys
d, h = sys.argv[1], float(sys.argv[2])
s = json.load(open(d + "/summary.json"))
for f in ("particles", "steps", "max_substeps", "particle_steps_per_s", "backend", "max_eq_plastic_strain"):
    print(f"taylor_{f}={s[f]}")
print(f"taylor_loop_s={s['step_loop_s']}")
try:
    import h5py, numpy as np
    with h5py.File(d + "/results.h5") as f:
        last = sorted(f["output"].keys())[-1]
        x = f["particles/position"][:] + f["output"][last]["displacement"][:]
    print(f"taylor_length_mm={(x[:, 2].max() + 0.5 * h) * 1e3}")
    print(f"taylor_radius_mm={(np.hypot(x[:, 0], x[:, 1]).max() + 0.5 * h) * 1e3}")
except Exception as e:  # no h5py here: the wall time still counts
    print(f"taylor_shape=not measured ({type(e).__name__})")
PY
  grep taylor_ "$RESULTS"
fi

# PD: bond-updates/s of PMB and LPS on a cubic lattice (the bench.sh case, larger), GPU vs CPU.
L=$(awk -v n="$PD_N" 'BEGIN{printf "%.6g", n*0.0005}')
result pd_n "$PD_N"
# pmb32 / lps32: the same with model.precision float32 (the GPU's float path, docs/cuda.md).
for model in pmb lps correspondence pmb32 lps32; do
  wanted pd || break
  step "PD $model, lattice $PD_N^3"
  case $model in
    correspondence) MODEL_LINE="{type: correspondence, horizon_factor: 3.015, stabilisation: {type: penalty, coefficient: 1}}" ;;
    *32) MODEL_LINE="{type: ${model%32}, horizon_factor: 3.015, precision: float32}" ;;
    *) MODEL_LINE="{type: $model, horizon_factor: 3.015}" ;;
  esac
  for leg in gpu cpu; do
    in_budget "pd_${model}_$leg" || continue
    backend=$GPU_BACKEND steps=$PD_GPU_STEPS
    [ $leg = cpu ] && backend=cpu steps=$PD_CPU_STEPS
    cat >"$WORK/pd_$model.yaml" <<YAML
name: device-bench-$model
specimen: {lattice: {dimension: 3, box: [0, 0, 0, $L, $L, $L], spacing: 0.0005}}
model: $MODEL_LINE
materials: [{name: m, density: 2200, youngs_modulus: 22.35 GPa, poisson_ratio: 0.25, fracture_energy: 1e6}]
initial: [{type: radial_velocity, center: [0, 0, 0], strain_rate: 10}]
time: {steps: $steps}
output: {every: 1000000, history_every: 1000000, results: false}
YAML
    dir="$WORK/pd_${model}_$leg"
    timeout "$(limit 200)" "${ENVP[@]}" "${LOADP[@]}" "$BIN/breccia-solve" "$WORK/pd_$model.yaml" -o "$dir" --backend "$backend" \
      --threads "$THREADS" --quiet >"$WORK/pd_${model}_$leg.log" 2>&1
    result "pd_${model}_${leg}_rc" "$?"
    tail -2 "$WORK/pd_${model}_$leg.log"
    [ -f "$dir/summary.json" ] && "$PYTHON" - "$dir/summary.json" "pd_${model}_$leg" >>"$RESULTS" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); k = sys.argv[2]
for f in ("backend", "threads", "particles", "mean_family_size", "setup_wall_s", "wall_s", "bond_updates_per_s"):
    print(f"{k}_{f}={s[f]}")
print(f"{k}_steps={s['steps_this_run']}")
PY
  done
done

# The atlas's time-stepping problems on both backends (breccia-atlas --backends cpu,cuda), lattice,
# m = 3: rows for docs/atlas/atlas.csv (append them with --append on the CPU machine's copy).
if wanted atlas && in_budget atlas; then
  step "atlas rows, CPU and GPU"
  ATLAS_BACKENDS=cpu,cuda
  [ "$DRY" = 1 ] && ATLAS_BACKENDS=cpu
  timeout "$(limit 200)" "${ENVP[@]}" "${LOADP[@]}" "$BIN/breccia-atlas" --problems wave_speed_bar,kalthoff_winkler \
    --kinds lattice --m 3 --no-stability --backends "$ATLAS_BACKENDS" --threads "$THREADS" $([ "$DRY" = 1 ] && echo --quick) \
    --work "$WORK/atlas" --csv "$OUT/atlas_gpu.csv" >"$WORK/atlas.log" 2>&1
  result atlas_rc "$?"
  result atlas_rows "$(($(wc -l <"$OUT/atlas_gpu.csv" 2>/dev/null || echo 1) - 1))"
  tail -5 "$WORK/atlas.log"
fi

# Last, as it is the slowest and optional: out-of-bounds and race checks of the MPS kernels.
if [ "${SANITIZER:-1}" = 1 ] && [ "$DRY" != 1 ] && command -v compute-sanitizer >/dev/null && in_budget sanitizer; then
  step "compute-sanitizer memcheck (test_mps_cuda, crack cases)"
  timeout "$(limit 150)" "${ENVP[@]}" compute-sanitizer --tool memcheck --error-exitcode 9 "${LOADP[@]}" "$BIN/test_mps_cuda" \
    --gtest_filter='MpsCuda.Sliding*:MpsCuda.Navier*Verlet*' >"$WORK/sanitizer.log" 2>&1
  rc=$?
  tail -5 "$WORK/sanitizer.log"
  result sanitizer_mps "rc $rc ($(grep -c "Invalid\|Race" "$WORK/sanitizer.log") reports)"
else
  result sanitizer_mps "not run"
fi
