#!/usr/bin/env bash
# First case (README.md, docs/tutorial.md): STEP file -> breccia-mesh -> breccia-place ->
# breccia-solve (case.yaml as shipped) -> breccia-post -> report.py.
#   VARIANT=test           : element size 2.5 mm (4,457 particles; the regression test, ~20 s)
#   VARIANT=quick|demo     : element size 1.5 mm (18,324 particles)
#   VARIANT=full           : element size 1 mm (56,870 particles)
# Environment: BRECCIA_BIN (executables), OUT (output folder), PYTHON, THREADS (optional).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
case "$VARIANT" in
  test)            SIZE="2.5 mm" ;;
  quick|demo)      SIZE="1.5 mm" ;;
  full)            SIZE="1 mm" ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full)" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
echo "== 1/4 mesh plate.step (element size $SIZE)"
"$BRECCIA_BIN/breccia-mesh" "$HERE/plate.step" -o "$OUT/plate.msh" --size "$SIZE" --threads 1 --quiet
echo "== 2/4 particles"
"$BRECCIA_BIN/breccia-place" "$OUT/plate.msh" -o "$OUT/particles.h5" --require-groups body,outer
echo "== 3/4 solve"
# The case file as shipped; only its particle file is pointed at this run's.
"$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$OUT/run" --set "specimen.particles=$OUT/particles.h5" \
  --threads "$THREADS" --quiet
echo "== 4/4 post-process"
"$BRECCIA_BIN/breccia-post" "$OUT/run" --cracks --fragments --energy --quiet > "$OUT/post.log"
"$PYTHON" "$HERE/report.py" "$OUT"
echo "results: $OUT/run/results.xdmf, $OUT/run/post/{cracks.vtp,fragments.vtu}; report: $OUT/report.json, $OUT/plate.png"
