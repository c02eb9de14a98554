#!/usr/bin/env bash
# The GPU session's one command (docs/cuda.md, "How to verify on a GPU"): ONE device call of at
# most 7 minutes. The checks run most important first, each with its own time cap, the caps
# summing to BUDGET_S (420 s):
#   agreement tests   test_solver_cuda 60, distributed_cuda 45 (2 ranks on the GPU against 1:
#                     test_distributed_cuda under the kit's mpirun), test_mps_cuda 40,
#                     test_mps_solid_cuda 30, test_atlas_backends 15
#   PD throughput     PMB and LPS on a 61^3 lattice, GPU 25 + CPU 15 each (GPU: 200 warm-up + 2,000
#                     steps with per-kernel CUDA-event times, stopped gently before the cap)
#   float32           PMB and LPS float32, GPU 12 each
#   concrete          the full concrete case (291,111 particles, gas, to 1 ms) on the GPU 41
#   MPS harmonics     0.125 mm, GPU 20 + CPU 25, histories compared
#   Taylor bar        32 across, GPU 20
#   sanitizer         compute-sanitizer memcheck: PD agreement tests on small plates 10, MPS 10
#   the rest          correspondence GPU/CPU, atlas GPU rows: only in the time the others left
# A check may use what earlier checks left unused (each must end by the sum of the caps so far),
# so a slow check never eats a later check's own cap; a check with no time left is skipped and
# listed as skipped. After every check $OUT/results.json is rewritten, a row is appended to
# $OUT/summary.md and $OUT/results.tar.gz is repacked, so a run cut short returns what it
# measured. $OUT holds 4 files: results.json, summary.md, results.tar.gz (every log, deck,
# summary, history and gtest XML report; no results.h5), device-check.log (written live).
#
#   1. Here, on the CPU machine (no device time):
#        scripts/device-check.sh prepare
#      builds breccia-solve, breccia-atlas and the four CUDA test executables for sm_90 in
#      build-device/ and packs them with the shared libraries they load and the case files the
#      run reads (with the full concrete case's particles, made by the main build's mesher and
#      placer) into one xz archive, build-device/kit/kit.tar.xz. The device machine has nvcc but no HDF5, yaml-cpp or
#      GoogleTest headers (nothing can be installed there), so the binaries travel instead.
#        BRECCIA_DEVICE_DRY=1 scripts/device-check.sh
#      rehearses everything here with the "GPU" legs on the CPU (small sizes,
#      OUT=/tmp/device-check-dry); the sanitizer skips (no GPU).
#   2. On the device machine, through the device tool's run:
#        command: bash scripts/device-check.sh     carry: ["build-device/kit"]     timeout_s: 480
#
# Environment: OUT (results folder), BRECCIA_DEVICE_DRY=1 (no GPU runs), BUDGET_S (420),
# ONLY=tests,pd,float32,concrete,mps,taylor,sanitizer,rest (run only these groups), PD_N (lattice edge,
# default 61: 227k particles, 2.8e7 bond entries), PD_WARMUP (200) and PD_TIMED_STEPS (2000) of
# the PMB and LPS GPU legs, PD_GPU_STEPS (500, the other GPU legs), PD_CPU_STEPS (20),
# MPS_SPACING (0.125 mm), MPS_END (15 us), TAYLOR_ACROSS (32), SANITIZER=0 (skip it).
set -uo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
KIT="$ROOT/build-device/kit"

if [ "${1:-}" = prepare ]; then
  set -e
  BUILD="$ROOT/build-device"
  LAUNCHER=()
  # ccache for the C++ only: with nvcc it once replayed a stale object after a header change,
  # and a stale kernel in the kit would cost a GPU session.
  command -v ccache >/dev/null && LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_CUDA_COMPILER_LAUNCHER=)
  cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DBRECCIA_STAGES=solver -DBRECCIA_CUDA=ON \
    -DCMAKE_CUDA_ARCHITECTURES=90 "${LAUNCHER[@]}" >"$BUILD.configure.log" 2>&1 || { cat "$BUILD.configure.log"; exit 1; }
  # Every executable the run starts (the CLI tests start breccia-solve and breccia-atlas: the
  # run points them at the kit's copies through BRECCIA_SOLVE_EXE and BRECCIA_ATLAS_EXE).
  EXES=(breccia-solve breccia-atlas test_solver_cuda test_mps_cuda test_mps_solid_cuda test_atlas_backends test_distributed_cuda)
  nice -n 10 cmake --build "$BUILD" -j"${JOBS:-2}" --target "${EXES[@]}"
  # The kit's files are staged in $STAGE and travel as one xz archive (below): the carry limit
  # (64 MiB) counts the working tree (about 15 MB) as well.
  STAGE="$BUILD/kit-files"
  rm -rf "$KIT" "$STAGE"
  mkdir -p "$KIT"
  KIT_OUT=$KIT KIT=$STAGE
  mkdir -p "$KIT/bin" "$KIT/lib" "$KIT/runtime" "$KIT/glibc" "$KIT/cases"
  for exe in "${EXES[@]}"; do cp "$BUILD/bin/$exe" "$KIT/bin/"; done
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
  # OpenMPI's launcher for the 2-rank check (the device image may have no MPI): orterun and
  # its plugins under ompi/ in the layout of Debian's prefix /usr, relocated at run time
  # (OPAL_PREFIX and the directories below; PMIx's plugins likewise), the libraries they load
  # in lib/ with the rest.
  if [ -x /usr/bin/orterun ]; then
    OMPI="$KIT/ompi" MA=/usr/lib/x86_64-linux-gnu
    mkdir -p "$OMPI/bin" "$OMPI/share" "$OMPI/etc" "$OMPI/pmix2"
    cp -L /usr/bin/orterun "$OMPI/bin/mpirun"
    cp -L /usr/bin/orted "$OMPI/bin/orted"
    mkdir -p "$OMPI/lib/openmpi3"
    cp -L "$MA"/openmpi/lib/openmpi3/*.so "$OMPI/lib/openmpi3/" 2>/dev/null || true
    cp -rL /usr/share/openmpi "$OMPI/share/" 2>/dev/null || true
    cp -rL /etc/openmpi/. "$OMPI/etc/" 2>/dev/null || true
    cp -rL "$MA/pmix2/lib" "$OMPI/pmix2/" 2>/dev/null || true
    cp -rL "$MA/pmix2/share" "$OMPI/pmix2/" 2>/dev/null || true
    rm -f "$OMPI/pmix2/lib/"*.a
    for f in "$OMPI/bin/"* "$OMPI/lib/openmpi3/"*.so "$OMPI/pmix2/lib/pmix/"*.so; do ldd "$f" 2>/dev/null; done |
      awk '$3 ~ /^\// {print $3}' | sort -u | while read -r lib; do
        name=$(basename "$lib")
        case "$name" in
          libc.so*|libm.so*|libpthread.so*|libdl.so*|librt.so*|libresolv.so*|libutil.so*|ld-linux*) ;;
          libstdc++.so*|libgcc_s.so*|libgomp.so*) [ -e "$KIT/runtime/$name" ] || cp -L "$lib" "$KIT/runtime/" ;;
          *) [ -e "$KIT/lib/$name" ] || cp -L "$lib" "$KIT/lib/" ;;
        esac
      done
  fi
  cp "$ROOT/cases/mps-harmonics/case.yaml" "$KIT/cases/mps-harmonics.yaml"
  cp "$ROOT/cases/mps-taylor-bar/case.yaml" "$KIT/cases/mps-taylor-bar.yaml"
  # The full concrete case's particles (291,111: make case-concrete-blast's specimen.yaml) for
  # the concrete leg, made here by the main build's mesher and placer: the device has neither
  # gmsh nor CGAL. Without them (MAIN_BIN) the kit goes without and the leg skips.
  MAIN_BIN=${MAIN_BIN:-$ROOT/build/bin}
  if [ -x "$MAIN_BIN/breccia-mesh" ] && [ -x "$MAIN_BIN/breccia-place" ]; then
    "$MAIN_BIN/breccia-mesh" "$ROOT/cases/concrete-blast/specimen.yaml" -o "$BUILD/concrete-full.msh" --threads 1 --quiet
    "$MAIN_BIN/breccia-place" "$BUILD/concrete-full.msh" -o "$KIT/cases/concrete-full.h5" --require-groups concrete,charge_hole >/dev/null
  else
    echo "no $MAIN_BIN/breccia-mesh or breccia-place: the kit has no concrete particles (the concrete leg will skip)"
  fi
  {
    echo "built: $(date -u +%FT%TZ) on $(hostname)"
    echo "commit: $(git -C "$ROOT" rev-parse HEAD 2>/dev/null) (+ uncommitted changes: $(git -C "$ROOT" status --porcelain 2>/dev/null | wc -l) paths)"
    /usr/local/cuda/bin/nvcc --version 2>/dev/null | tail -2
    (cd "$KIT" && find . -type f ! -name MANIFEST | sort)
  } >"$KIT/MANIFEST"
  du -sh "$KIT"
  # xz: 35 MB of gzip became 19 MB (2026-12-06), which leaves room in the carry for the
  # concrete particles. The device unpacks it with tar, or with Python's tarfile where tar
  # has no xz.
  rm -f "$KIT_OUT/kit.tar.gz"
  XZ_OPT="-6 -T${JOBS:-2}" tar -cJf "$KIT_OUT/kit.tar.xz" -C "$KIT" .
  cp "$KIT/MANIFEST" "$KIT_OUT/MANIFEST"
  du -sh "$KIT_OUT"
  echo "kit ready: carry [\"build-device/kit\"] and run 'bash scripts/device-check.sh' on the device"
  exit 0
fi

DRY=${BRECCIA_DEVICE_DRY:-0}
if [ "$DRY" = 1 ]; then OUT=${OUT:-/tmp/device-check-dry}; else OUT=${OUT:-$ROOT/runs/device-check}; fi
mkdir -p "$OUT"
rm -f "$OUT/results.json" "$OUT/summary.md" "$OUT/results.tar.gz" "$OUT/device-check.log"
WORK=$(mktemp -d /tmp/device-check.XXXXXX)
# The carried kit is one archive (prepare above): unpacked outside WORK, which is packed back.
KIT_FILES=
KIT_ARCHIVE=$(ls "$KIT/kit.tar.xz" "$KIT/kit.tar.gz" 2>/dev/null | head -1)
if [ -n "$KIT_ARCHIVE" ]; then
  KIT_FILES=$(mktemp -d /tmp/device-kit.XXXXXX)
  if tar -xf "$KIT_ARCHIVE" -C "$KIT_FILES" 2>/dev/null ||
     python3 -c 'import sys, tarfile; tarfile.open(sys.argv[1]).extractall(sys.argv[2])' "$KIT_ARCHIVE" "$KIT_FILES"; then
    KIT=$KIT_FILES
  fi
fi
exec > >(tee -a "$OUT/device-check.log") 2>&1
START=$(date +%s)
BUDGET=${BUDGET_S:-420}
step() { echo; echo "== [$(($(date +%s) - START)) s] $*"; }
RESULTS="$WORK/results.txt"  # key=value as measured; results.json is made from it after every check
: >"$RESULTS"
result() { echo "$1=$2" >>"$RESULTS"; }
THREADS=$(nproc)
PYTHON=${PYTHON:-python3}  # the device's python3 has numpy; here /usr/bin/python3 does
"$PYTHON" -c "import numpy" 2>/dev/null || PYTHON=/usr/bin/python3
if [ "$DRY" = 1 ]; then
  PD_N=${PD_N:-21}; PD_GPU_STEPS=${PD_GPU_STEPS:-20}; PD_CPU_STEPS=${PD_CPU_STEPS:-10}
  PD_WARMUP=${PD_WARMUP:-5}; PD_TIMED_STEPS=${PD_TIMED_STEPS:-20}
  MPS_SPACING=${MPS_SPACING:-0.25}; MPS_END=${MPS_END:-3 us}; TAYLOR_ACROSS=${TAYLOR_ACROSS:-4}
else
  # Sized for the caps: the PD set-up (families, bond coefficients, stable step) took 13.7 s
  # for 41^3 on 2 cores here and grows with the particles, so 81^3 (531k, 7.7x) could not be
  # set up twice in 25 s; 61^3 (227k, 2.8e7 bond entries) still overflows the GPU's L2 many
  # times. MPS to 15 us (1,441 steps): the rates are the figures; the CPU leg fits its 35 s.
  # The PMB and LPS GPU legs run PD_WARMUP + PD_TIMED_STEPS steps with per-kernel CUDA-event
  # times over the last PD_TIMED_STEPS (breccia-solve --kernel-times); the other GPU legs
  # PD_GPU_STEPS, timed after a tenth of them.
  PD_N=${PD_N:-61}; PD_GPU_STEPS=${PD_GPU_STEPS:-500}; PD_CPU_STEPS=${PD_CPU_STEPS:-20}
  PD_WARMUP=${PD_WARMUP:-200}; PD_TIMED_STEPS=${PD_TIMED_STEPS:-2000}
  MPS_SPACING=${MPS_SPACING:-0.125}; MPS_END=${MPS_END:-15 us}; TAYLOR_ACROSS=${TAYLOR_ACROSS:-32}
fi
GPU_BACKEND=cuda
[ "$DRY" = 1 ] && GPU_BACKEND=cpu  # the rehearsal runs the "GPU" legs on the CPU to test the plumbing

# results.txt -> results.json (flat key: value, plus "skipped": {check: reason}), written to a
# temporary name and moved so a cut-off never leaves half a file; then the archive, repacked.
publish() {
  "$PYTHON" - "$RESULTS" "$OUT/results.json" <<'PY'
import json, os, sys
res, skipped = {}, {}
for line in open(sys.argv[1]):
    if "=" not in line:
        continue
    k, v = line.rstrip("\n").split("=", 1)
    try: v = float(v) if ("." in v or "e" in v.lower()) else int(v)
    except ValueError: pass
    res[k] = v
    if k.startswith("skipped_"):
        skipped[k[len("skipped_"):]] = v
res["skipped"] = skipped
json.dump(res, open(sys.argv[2] + ".tmp", "w"), indent=1, sort_keys=True)
os.replace(sys.argv[2] + ".tmp", sys.argv[2])
PY
  # Logs, decks, summaries, histories, gtest XML; no results.h5 (tens of MB at 0.125 mm).
  tar -czf "$OUT/results.tar.gz.tmp" --exclude='*.h5' -C "$WORK" . 2>/dev/null && mv "$OUT/results.tar.gz.tmp" "$OUT/results.tar.gz"
}
FINISHED=0
finish() {
  [ "$FINISHED" = 1 ] && return
  FINISHED=1
  result elapsed_s $(($(date +%s) - START))
  step "results (elapsed $(($(date +%s) - START)) s)"
  {
    echo
    echo "elapsed: $(($(date +%s) - START)) s of a $BUDGET s check budget"
    echo
    local skipped
    skipped=$(grep '^skipped_' "$RESULTS" | sed 's/^skipped_//; s/=/ (/; s/$/)/' | paste -sd ';' - | sed 's/;/; /g')
    echo "skipped: ${skipped:-none}"
  } >>"$OUT/summary.md"
  publish
  cat "$OUT/summary.md"
  ls -l "$OUT"
  rm -rf "$WORK" ${KIT_FILES:+"$KIT_FILES"}
}
trap finish EXIT
# A signal may have stopped tee too (a killer of the process group): the log is then appended
# to directly, and a write to the dead pipe must not end the packing.
trap '' PIPE
trap 'trap "" TERM INT HUP; exec >>"$OUT/device-check.log" 2>&1; echo "signal: stopping the running check, packing what was measured"
      [ -n "${CHILD:-}" ] && kill -TERM "$CHILD" 2>/dev/null
      [ -n "${CHECK:-}" ] && result stopped_during "$CHECK" && echo "| $CHECK | stopped by a signal | | |" >>"$OUT/summary.md"
      exit 143' TERM INT HUP
result dry "$DRY"
result budget_s "$BUDGET"
{
  echo "# device-check results$([ "$DRY" = 1 ] && echo " (DRY: no GPU; the GPU legs ran on the CPU)")"
  echo
} >"$OUT/summary.md"

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
      { cmake --build /tmp/breccia-build -j"$THREADS" --target test_distributed_cuda >>/tmp/breccia-build.log 2>&1 ||
        echo "test_distributed_cuda not built here (no MPI?): its check is skipped"; } &&
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
HAVE_GPU=0
[ -n "$DEVICE" ] && [ "$DEVICE" != none ] && HAVE_GPU=1
SANITIZER_EXE=$(command -v compute-sanitizer || ls /usr/local/cuda/bin/compute-sanitizer 2>/dev/null)
# The CLI tests (test_mps_cuda, test_atlas_backends) start breccia-solve and breccia-atlas: the
# build's paths compiled into them do not exist here, so they take the kit's (with the loader
# in front where the kit's glibc is used; LD_LIBRARY_PATH reaches them through the environment).
export BRECCIA_SOLVE_EXE="${LOADP[*]:+${LOADP[*]} }$BIN/breccia-solve"
export BRECCIA_ATLAS_EXE="${LOADP[*]:+${LOADP[*]} }$BIN/breccia-atlas"
{
  echo "device: ${DEVICE:-none}; binaries: $MODE ($BIN); $THREADS cores; $(cat "$KIT/MANIFEST" 2>/dev/null | head -2 | paste -sd ';' - | sed 's/;/; /')"
  echo
  echo "| check | status | s | results |"
  echo "|---|---|---|---|"
} >>"$OUT/summary.md"

# check GROUP NAME CAP FUNCTION [ARGS]: FUNCTION runs with T, its seconds: up to the sum of the
# caps so far (CAP 0: only the time the others left, at least 20 s), never past the budget.
CHECK_T0=$(date +%s) CHECK= FAILED_CHECKS=
PLANNED=0
wanted() { [ -z "${ONLY:-}" ] || [[ ",$ONLY," == *",$1,"* ]]; }
skip() { result "skipped_$CHECK" "$1"; echo "skipped: $CHECK ($1)"; SKIPPED=1; }
check() {
  local group=$1 name=$2 cap=$3; shift 3
  CHECK=$name SKIPPED=0
  PLANNED=$((PLANNED + cap))
  local now=$(($(date +%s) - CHECK_T0)) deadline=$((PLANNED < BUDGET ? PLANNED : BUDGET)) least=5
  [ "$cap" = 0 ] && deadline=$BUDGET least=20
  T=$((deadline - now))
  local status took=0 mark
  mark=$(wc -l <"$RESULTS")
  if ! wanted "$group"; then
    skip "not in ONLY=$ONLY"
  elif [ "$T" -lt "$least" ]; then
    skip "budget spent: $now of $BUDGET s used"
  fi
  if [ "$SKIPPED" = 0 ]; then
    step "$name (up to $T s)"
    local t0=$(date +%s)
    "$@"
    local rc=$?
    took=$(($(date +%s) - t0))
    result "${name}_s" "$took"
    status="rc $rc"
    [ "$rc" = 124 ] && status="cut off at $T s" && result "${name}_cut_off_s" "$T"
    # Failed checks make the script's exit status non-zero at the end (the run goes on: each
    # check's figures count on their own); one cut off by its time cap is not a failure.
    [ "$rc" != 0 ] && [ "$rc" != 124 ] && FAILED_CHECKS="$FAILED_CHECKS $name"
  fi
  [ "$SKIPPED" = 1 ] && status=skipped
  # The row: what this check added to the results (its skip reason included).
  echo "| $name | $status | $took | $(tail -n +$((mark + 1)) "$RESULTS" | grep -v "^${name}_s=" | paste -sd ';' - | sed 's/;/; /g') |" >>"$OUT/summary.md"
  CHECK=
  publish
}
# A check's command runs in the background and the script waits for it: bash handles a TERM
# only between commands, and wait is one it interrupts, so a stopped run packs at once.
CHILD=
timed() { timeout "$T" "$@" & CHILD=$!; wait "$CHILD"; local rc=$?; CHILD=; return $rc; }
run_bin_t() { timed "${ENVP[@]}" "${LOADP[@]}" "$@"; }
# A time loop stopped gently: Ctrl-C (SIGINT) 10 s before the cap, on which breccia-solve ends
# its loop and writes summary.json over the steps done (status interrupted, exit 130), then a
# kill at the cap. A GPU slower than planned still returns its rate and kernel times.
run_bin_int() {
  local soft=$((T > 20 ? T - 10 : T))
  timeout -s INT -k $((T - soft + 1)) "$soft" "${ENVP[@]}" "${LOADP[@]}" "$@" & CHILD=$!
  wait "$CHILD"; local rc=$?; CHILD=; return $rc
}

# gtest: PASSED/FAILED/SKIPPED counts into the results, the XML report into the archive.
run_tests() {  # run_tests NAME [gtest args]
  local name=$1; shift
  # A binary the kit or the fallback build lacks is a skip with its name, not a failure (rc 127).
  [ -x "$BIN/$name" ] || { skip "$name not built"; return 0; }
  timed env BRECCIA_CUDA_SYNC=1 "${ENVP[@]}" "${LOADP[@]}" "$BIN/$name" --gtest_output=xml:"$WORK/$name.xml" "$@" >"$WORK/$name.log" 2>&1
  local rc=$?
  grep -E "^\[ +(OK|FAILED|SKIPPED) +\]|\[(mps )?cuda\]|Failure|error" "$WORK/$name.log" | head -80
  local passed failed skipped
  passed=$(grep -c "^\[       OK \]" "$WORK/$name.log"); failed=$(grep -c "^\[  FAILED  \] [A-Za-z0-9_]*\.[A-Za-z0-9_]* (" "$WORK/$name.log")
  skipped=$(grep -c "^\[  SKIPPED \] [A-Za-z0-9_]*\.[A-Za-z0-9_]* (" "$WORK/$name.log")
  result "$name" "rc $rc: $passed passed, $failed failed, $skipped skipped"
  echo "$name: rc $rc: $passed passed, $failed failed, $skipped skipped"
  return $rc
}
# A GPU leg needs a GPU, except in the rehearsal (which runs it on the CPU).
gpu_leg_possible() { [ "$1" != gpu ] || [ "$DRY" = 1 ] || [ "$HAVE_GPU" = 1 ] || { skip "no GPU"; false; }; }

# A breccia-solve run's summary.json into the results under KEY: rate, set-up and loop times,
# status, the set-up's phases, the gas's share, the device memory (bytes per particle, the
# particles of that kind that would fit) and the first 8 kernels' microseconds per timed step
# (all of them are in the archived summary.json). A run stopped at its cap by the gentle
# stop (timeout's 124, the run's own 130) counts as done, its figures over the steps it made.
summary_results() {  # summary_results DIR KEY RC
  local dir=$1 k=$2 rc=$3
  [ -f "$dir/summary.json" ] && "$PYTHON" - "$dir/summary.json" "$k" "${DEVICE:-none}" >>"$RESULTS" <<'PY'
import json, re, sys
s = json.load(open(sys.argv[1])); k = sys.argv[2]
name = lambda text: re.sub("[^A-Za-z0-9]+", "_", text).strip("_")
for f in ("backend", "threads", "particles", "setup_wall_s", "wall_s", "bond_updates_per_s", "status",
          "time_s", "gas_share_of_loop", "results_header_wall_s", "final_checkpoint_wall_s"):
    if f in s:
        print(f"{k}_{f}={s[f]}")
print(f"{k}_steps={s['steps_this_run']}")
for phase, seconds in s.get("setup_phases_s", {}).items():
    print(f"{k}_setup_{name(phase)}_s={seconds:.3f}")
d = s.get("device_memory")  # the GPU's: bytes per particle and how many such particles fit
if d:
    for f in ("system_bytes", "bytes_per_particle", "free_before_bytes", "particles_that_would_fit"):
        print(f"{k}_device_{f}={d[f]}")
# The GPU's rate against docs/cuda.md's bandwidth floor (bytes streamed per bond-update on the
# path this lattice runs: one horizon, no diagnostics between outputs) and the GPU issue's
# targets (3x CabanaPD's published H100 rates: PMB 7e10, LPS 4.2e10 bond-updates/s).
model = re.sub(r"^pd_|_gpu$", "", k)
floor_bytes = {"pmb": 25, "lps": 46, "pmb32": 17, "lps32": 30, "pmbsell": 25, "lpssell": 46}.get(model)
device = " ".join(sys.argv[3:])
bandwidth = 4.8e12 if "H200" in device else 3.35e12 if "H100" in device else None
if s.get("backend") == "cuda" and floor_bytes and bandwidth:
    rate = s["bond_updates_per_s"]
    print(f"{k}_bandwidth_floor={bandwidth / floor_bytes:.3g}")
    print(f"{k}_fraction_of_floor={rate * floor_bytes / bandwidth:.3f}")
    target = {"pmb": 7e10, "lps": 4.2e10}.get(model.replace("sell", "").replace("32", ""))
    if target:
        print(f"{k}_fraction_of_target={rate / target:.3f}")
t = s.get("kernel_times")
if t:
    print(f"{k}_kernel_steps_timed={t['steps_timed']}")
    print(f"{k}_kernel_all_us_per_step={1e6 * t['seconds'] / max(t['steps_timed'], 1):.2f}")
    for kern in t["kernels"][:8]:
        print(f"{k}_kernel_{name(kern['name'])}_us_per_step={kern['us_per_step']:.2f}")
PY
  if [ "$rc" = 124 ] || [ "$rc" = 130 ]; then
    grep -q '"status": "interrupted"' "$dir/summary.json" 2>/dev/null && result "${k}_stopped_at_cap" 1 && return 0
  fi
  return "$rc"
}

# The full concrete case on the GPU, as shipped (to 1 ms, the gas load, quasi-brittle bonds,
# results every 200 steps) on the kit's 291,111 particles: one process, its set-up on the
# device machine's cores, kernel times after 50 steps. The stages before and after the solver
# (breccia-mesh, breccia-place, breccia-post) need gmsh, CGAL and VTK, which the device lacks:
# they are timed on the CPU machine (docs/performance.md, "The whole chain"). The rehearsal
# runs it to CONCRETE_DRY_END (2 us) on the CPU.
concrete_leg() {
  gpu_leg_possible gpu || return 0
  local particles="$KIT/cases/concrete-full.h5" dir="$WORK/concrete_full_gpu" extra=()
  [ -f "$particles" ] || { skip "no concrete particles in the kit"; return 0; }
  [ "$DRY" = 1 ] && extra=(--set "time.end=${CONCRETE_DRY_END:-2 us}")
  run_bin_int "$BIN/breccia-solve" "$ROOT/cases/concrete-blast/case.yaml" -o "$dir" --set "specimen.particles=$particles" \
    --backend "$GPU_BACKEND" --threads "$THREADS" --kernel-times 50 "${extra[@]}" >"$WORK/concrete_full_gpu.log" 2>&1
  local rc=$?
  grep -v "^step " "$WORK/concrete_full_gpu.log" | tail -25
  summary_results "$dir" concrete_full_gpu "$rc"
}

# PD: bond-updates/s on a cubic lattice (the bench.sh case, larger). MODEL: pmb, lps,
# correspondence, pmb32/lps32 (model.precision float32, the GPU's float path) or
# pmbsell/lpssell (model.cuda_layout: sell), or lps2d/lps2dsell: a 2D LPS square with fracture
# (each complete family's s0 rescaled, so the halves differ: the dual-horizon pass) of about as
# many particles as the cube, on the CSR and on the layout.
PD_L=$(awk -v n="$PD_N" 'BEGIN{printf "%.6g", n*0.0005}')
PD2_L=$(awk -v n="$PD_N" 'BEGIN{printf "%.6g", int(n^1.5 + 0.5)*0.0005}')
result pd_n "$PD_N"
pd_leg() {  # pd_leg MODEL gpu|cpu
  local model=$1 leg=$2 backend=$GPU_BACKEND steps=$PD_GPU_STEPS model_line warmup timing=()
  local specimen="{lattice: {dimension: 3, box: [0, 0, 0, $PD_L, $PD_L, $PD_L], spacing: 0.0005}}"
  gpu_leg_possible "$leg" || return 0
  warmup=$((PD_GPU_STEPS / 10))
  case $model in pmb|lps) steps=$((PD_WARMUP + PD_TIMED_STEPS)) warmup=$PD_WARMUP ;; esac
  [ "$leg" = gpu ] && timing=(--kernel-times "$warmup")  # on the CPU (the rehearsal) a note, nothing timed
  [ "$leg" = cpu ] && backend=cpu steps=$PD_CPU_STEPS
  case $model in
    lps2d*)  # dual horizon (variable halves); lps2dsell: over the layout
      specimen="{lattice: {dimension: 2, box: [0, 0, $PD2_L, $PD2_L], spacing: 0.0005, thickness: 0.0005}}"
      model_line="{type: lps, planar: plane_strain, horizon_factor: 3.015$([ "$model" = lps2dsell ] && echo ", cuda_layout: sell")}" ;;
    correspondence) model_line="{type: correspondence, horizon_factor: 3.015, stabilisation: {type: penalty, coefficient: 1}}" ;;
    *32) model_line="{type: ${model%32}, horizon_factor: 3.015, precision: float32}" ;;
    *sell) model_line="{type: ${model%sell}, horizon_factor: 3.015, cuda_layout: sell}" ;;  # SELL-C-sigma bonds
    *) model_line="{type: $model, horizon_factor: 3.015}" ;;
  esac
  local k="pd_${model}_$leg" dir="$WORK/pd_${model}_$leg"
  cat >"$WORK/$k.yaml" <<YAML
name: device-bench-$model
specimen: $specimen
model: $model_line
materials: [{name: m, density: 2200, youngs_modulus: 22.35 GPa, poisson_ratio: 0.25, fracture_energy: 1e6}]
initial: [{type: radial_velocity, center: [0, 0, 0], strain_rate: 10}]
time: {steps: $steps}
output: {every: 1000000, history_every: 1000000, results: false}
YAML
  run_bin_int "$BIN/breccia-solve" "$WORK/$k.yaml" -o "$dir" --backend "$backend" --threads "$THREADS" \
    "${timing[@]}" >"$WORK/$k.log" 2>&1
  local rc=$?
  grep -v "^step " "$WORK/$k.log" | tail -20  # the kernel table (GPU) or the note, and the last line
  summary_results "$dir" "$k" "$rc"
}

# MPS: the harmonics case at MPS_SPACING, GPU then CPU on every core; histories compared.
sed -e "s/spacing: 0.25 mm/spacing: $MPS_SPACING mm/" -e "s/time: {end: 30 us/time: {end: $MPS_END/" \
  "$KIT/cases/mps-harmonics.yaml" >"$WORK/harmonics.yaml" 2>/dev/null ||
  sed -e "s/spacing: 0.25 mm/spacing: $MPS_SPACING mm/" -e "s/time: {end: 30 us/time: {end: $MPS_END/" \
    "$ROOT/cases/mps-harmonics/case.yaml" >"$WORK/harmonics.yaml"
result mps_spacing_mm "$MPS_SPACING"
mps_leg() {  # mps_leg gpu|cpu
  local leg=$1 backend=$GPU_BACKEND dir="$WORK/mps_$1"
  gpu_leg_possible "$leg" || return 0
  [ "$leg" = cpu ] && backend=cpu
  run_bin_t "$BIN/breccia-solve" "$WORK/harmonics.yaml" -o "$dir" --backend "$backend" --threads "$THREADS" >"$WORK/mps_$leg.log" 2>&1
  local rc=$?
  grep -E "^mps:|error|warning" "$WORK/mps_$leg.log" | tail -4
  [ -f "$dir/summary.json" ] && "$PYTHON" - "$dir/summary.json" "mps_$leg" >>"$RESULTS" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); k = sys.argv[2]
for f in ("particles", "steps", "wall_time_s", "particle_steps_per_s", "max_slipping_fraction"):
    print(f"{k}_{f}={s[f]}")
print(f"{k}_loop_s={s['step_loop_s']}")
print(f"{k}_backend={s.get('backend', '?')}")
PY
  [ "$leg" = cpu ] && [ -f "$WORK/mps_gpu/history.csv" ] && [ -f "$WORK/mps_cpu/history.csv" ] &&
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
  return $rc
}

# MPS stress formulation: the Taylor bar at TAYLOR_ACROSS particles across (32: about 130k
# particles, finer than any CPU run), GPU only; length and face radius at the end as
# cases/mps-taylor-bar/report.py measures them (where h5py is present).
taylor() {
  gpu_leg_possible gpu || return 0
  local case_file="$KIT/cases/mps-taylor-bar.yaml" h
  [ -f "$case_file" ] || case_file="$ROOT/cases/mps-taylor-bar/case.yaml"
  read -r h < <("$PYTHON" -c "print(repr(6.4e-3 / $TAYLOR_ACROSS))")
  # The spacing, output interval and end through --set (breccia-solve applies them before the
  # MPS branch): a sed of the deck's text silently matched nothing once the case's spelling
  # changed, and the leg then ran the shipped 8-across bar under a "32 across" label.
  result taylor_across "$TAYLOR_ACROSS"
  run_bin_t "$BIN/breccia-solve" "$case_file" -o "$WORK/taylor" --backend "$GPU_BACKEND" --threads "$THREADS" \
    --set "specimen.bodies.spacing=$h" --set "output.every=1000000" --set "time.end=${TAYLOR_END:-80 us}" >"$WORK/taylor.log" 2>&1
  local rc=$?
  # The bar as run: its spacing from case_as_run.yaml (the overrides applied), checked against h.
  if [ -f "$WORK/taylor/case_as_run.yaml" ] && ! grep -q "spacing: $h\b" "$WORK/taylor/case_as_run.yaml"; then
    echo "taylor: the run's spacing is not $h (case_as_run.yaml)"; result taylor_spacing_mismatch 1; rc=9
  fi
  grep -E "^mps|error" "$WORK/taylor.log" | tail -4
  [ -f "$WORK/taylor/summary.json" ] && "$PYTHON" - "$WORK/taylor" "$h" >>"$RESULTS" <<'PY'
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
  return $rc
}

# compute-sanitizer memcheck (out-of-bounds and misaligned accesses, device-side errors) of
# agreement tests on small cases: PD on the 800-particle plates and the 567-particle LPS block
# (crack growth, pressure, indenter, the load kernels), MPS on its crack cases.
sanitize() {  # sanitize NAME EXE FILTER
  local name=$1 exe=$2 filter=$3
  [ "${SANITIZER:-1}" = 1 ] || { skip "SANITIZER=0"; return 0; }
  [ "$DRY" = 1 ] && { skip "no GPU (rehearsal)"; return 0; }
  [ "$HAVE_GPU" = 1 ] || { skip "no GPU"; return 0; }
  [ -n "$SANITIZER_EXE" ] || { skip "compute-sanitizer absent"; return 0; }
  timed "${ENVP[@]}" "$SANITIZER_EXE" --tool memcheck --error-exitcode 9 "${LOADP[@]}" "$BIN/$exe" \
    --gtest_filter="$filter" >"$WORK/$name.log" 2>&1
  local rc=$?
  tail -5 "$WORK/$name.log"
  result "$name" "rc $rc: $(grep -c "^\[       OK \]" "$WORK/$name.log") tests passed, $(grep -c "Invalid\|Race\|Misaligned\|Error:" "$WORK/$name.log") reports"
  return $rc
}

# The atlas's time-stepping problems on both backends (lattice, m = 3): rows for
# docs/atlas/atlas.csv (append them with --append on the CPU machine's copy).
atlas_rows() {
  gpu_leg_possible gpu || return 0
  local backends=cpu,cuda
  [ "$DRY" = 1 ] && backends=cpu
  run_bin_t "$BIN/breccia-atlas" --problems wave_speed_bar,kalthoff_winkler --kinds lattice --m 3 --no-stability \
    --backends "$backends" --threads "$THREADS" $([ "$DRY" = 1 ] && echo --quick) --work "$WORK/atlas" --csv "$WORK/atlas_gpu.csv" >"$WORK/atlas.log" 2>&1
  local rc=$?
  result atlas_rows "$(($(wc -l <"$WORK/atlas_gpu.csv" 2>/dev/null || echo 1) - 1))"
  tail -5 "$WORK/atlas.log"
  return $rc
}

# --backend cuda under mpirun (docs/parallel.md, GPUs): test_distributed_cuda runs breccia-solve
# on 2 ranks sharing the GPU and on 1 process, and compares the files byte for byte. mpirun:
# the kit's OpenMPI (relocated), else the device's own; none: skipped with the reason.
distributed_cuda() {
  gpu_leg_possible gpu || return 0
  local mpirun=""
  if [ -x "$KIT/ompi/bin/mpirun" ]; then
    export OPAL_PREFIX="$KIT/ompi" OPAL_BINDIR="$KIT/ompi/bin" OPAL_LIBDIR="$KIT/lib" OPAL_PKGLIBDIR="$KIT/ompi/lib/openmpi3" \
      OPAL_DATADIR="$KIT/ompi/share" OPAL_PKGDATADIR="$KIT/ompi/share/openmpi" OPAL_SYSCONFDIR="$KIT/ompi/etc" \
      PMIX_PREFIX="$KIT/ompi/pmix2" PMIX_LIBDIR="$KIT/ompi/pmix2/lib" PMIX_PKGLIBDIR="$KIT/ompi/pmix2/lib/pmix" \
      PMIX_PKGDATADIR="$KIT/ompi/pmix2/share/pmix" PMIX_SYSCONFDIR="$KIT/ompi/pmix2/share" \
      OMPI_MCA_mca_base_component_show_load_errors=0
    mpirun="${LOADP[*]:+${LOADP[*]} }$KIT/ompi/bin/mpirun"
  elif command -v mpirun >/dev/null; then
    mpirun=$(command -v mpirun)
  fi
  [ -n "$mpirun" ] || { skip "no mpirun (kit or device)"; return 0; }
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 \
    OMPI_MCA_btl_vader_single_copy_mechanism=none
  # The launcher itself first: a relocation that fails says so here, not as a test failure.
  if ! timeout 30 "${ENVP[@]}" $mpirun -np 2 "${LOADP[@]}" "$BIN/breccia-solve" --help >"$WORK/mpirun_probe.log" 2>&1; then
    tail -20 "$WORK/mpirun_probe.log"
    result distributed_cuda_mpirun "failed: $mpirun"
    skip "mpirun does not start here (log in the archive)"
    return 0
  fi
  result distributed_cuda_mpirun "$mpirun"
  export BRECCIA_MPIEXEC="$mpirun"  # test_distributed_cuda's launcher (distributed_compare.hpp)
  run_tests test_distributed_cuda
}

# Most important first; the caps sum to 420 s (the default BUDGET_S). The sanitizer's are short:
# on the device's gVisor runtime compute-sanitizer was seen refusing the GPU at once ("Device not
# supported", the device tool's notes of 2026-11-04), so its checks take seconds either way.
check tests test_solver_cuda 60 run_tests test_solver_cuda
check tests distributed_cuda 45 distributed_cuda
check tests test_mps_cuda 40 run_tests test_mps_cuda
check tests test_mps_solid_cuda 30 run_tests test_mps_solid_cuda
check tests test_atlas_backends 15 run_tests test_atlas_backends
check pd pd_pmb_gpu 25 pd_leg pmb gpu
check pd pd_pmb_cpu 15 pd_leg pmb cpu
check pd pd_lps_gpu 25 pd_leg lps gpu
check pd pd_lps_cpu 15 pd_leg lps cpu
check float32 pd_pmb32_gpu 12 pd_leg pmb32 gpu
check float32 pd_lps32_gpu 12 pd_leg lps32 gpu
check concrete concrete_full_gpu 41 concrete_leg
check mps mps_gpu 20 mps_leg gpu
check mps mps_cpu 25 mps_leg cpu
check taylor taylor 20 taylor
check sanitizer sanitizer_pd 10 sanitize sanitizer_pd test_solver_cuda \
  'CudaBackend.PmbCrackBreaksTheSameBondsAsOnTheCpu:CudaBackend.LpsBlockWithPressureAndIndenterMatchesTheCpuOver1000Steps:LoadKernels.*'
check sanitizer sanitizer_mps 10 sanitize sanitizer_mps test_mps_cuda 'MpsCuda.Sliding*:MpsCuda.Navier*Verlet*'
check rest pd_correspondence_gpu 0 pd_leg correspondence gpu
check rest pd_correspondence_cpu 0 pd_leg correspondence cpu
check rest atlas_rows 0 atlas_rows
# The SELL-C-sigma bond layout (model.cuda_layout: sell; docs/cuda.md): the same lattice as
# pd_pmb_gpu and pd_lps_gpu, its rate against theirs.
check rest pd_pmbsell_gpu 0 pd_leg pmbsell gpu
check rest pd_lpssell_gpu 0 pd_leg lpssell gpu
# Variable horizons: the dual-horizon pass on the CSR and on the layout (a 2D LPS square).
check rest pd_lps2d_gpu 0 pd_leg lps2d gpu
check rest pd_lps2dsell_gpu 0 pd_leg lps2dsell gpu
finish  # (the EXIT trap then does nothing)
if [ -n "${FAILED_CHECKS:-}" ]; then
  echo "device-check: failed:$FAILED_CHECKS (results.json and summary.md hold every check's figures)"
  exit 1
fi
