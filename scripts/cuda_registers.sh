#!/usr/bin/env bash
# Register use and spills of every CUDA kernel of the PD backend, from ptxas -v (no GPU needed):
# compiles solver/cuda/src/cuda_backend.cu for sm_90 with the build's flags and prints a
# Markdown table (docs/cuda.md, "Registers"). Usage: scripts/cuda_registers.sh [BUILD_DIR]
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="$(cd "${1:-$ROOT/build}" && pwd)"
NVCC=${NVCC:-/usr/local/cuda/bin/nvcc}
DIR="$BUILD/solver/cuda"
[ -f "$DIR/CMakeFiles/breccia_solver_cuda.dir/includes_CUDA.rsp" ] || { echo "cuda_registers: configure $BUILD with CUDA first (make build)"; exit 2; }
LOG=$(mktemp)
trap 'rm -f "$LOG" "$LOG.o"' EXIT
# nvcc's own messages when it fails (they went to the log alone, which set -e then left behind).
if ! ( cd "$DIR" && "$NVCC" -O3 -DNDEBUG --generate-code=arch=compute_90,code=sm_90 --fmad=false --expt-relaxed-constexpr \
    -std=c++20 --options-file CMakeFiles/breccia_solver_cuda.dir/includes_CUDA.rsp -Xptxas -v \
    -c "$ROOT/solver/cuda/src/cuda_backend.cu" -o "$LOG.o" ) >"$LOG" 2>&1; then
  cat "$LOG" >&2
  echo "cuda_registers: nvcc failed (above)" >&2
  exit 1
fi
"${PYTHON:-/usr/bin/python3}" - "$LOG" <<'PY'
import re, subprocess, sys
rows, cur = [], None
for l in open(sys.argv[1]):
    m = re.search(r"Compiling entry function '([^']+)'", l)
    if m:
        cur = {"name": m.group(1)}; rows.append(cur); continue
    m = re.search(r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads", l)
    if m and cur is not None and "stack" not in cur:
        cur["stack"], cur["ss"], cur["sl"] = m.groups(); continue
    m = re.search(r"Used (\d+) registers", l)
    if m and cur is not None and "regs" not in cur:
        cur["regs"] = m.group(1)
names = subprocess.run(["c++filt"], input="\n".join(r["name"] for r in rows), capture_output=True, text=True).stdout.splitlines()
print("| kernel (sm_90) | registers | spill stores / loads (B) | stack (B) |\n|---|---|---|---|")
for r, n in sorted(zip(rows, names), key=lambda x: x[1]):
    n = re.sub(r"\(.*\)$", "", n.replace("breccia::solver::", "").replace("(anonymous namespace)::", "").replace("void ", ""))
    print(f"| `{n}` | {r.get('regs')} | {r.get('ss')} / {r.get('sl')} | {r.get('stack')} |")
PY
rm -f "$LOG" "$LOG.o"
