#!/usr/bin/env bash
# Concrete block with a charge hole, end to end: spec -> mesh -> particles -> PD -> post.
# Environment (scripts/run_case.sh): BRECCIA_BIN, OUT, VARIANT (quick|demo|full), PYTHON.
set -euo pipefail
case "$VARIANT" in
  quick) SPEC=specimen-quick.yaml; END="150 us" ;;
  demo)  SPEC=specimen-demo.yaml;  END="250 us" ;;
  full)  SPEC=specimen.yaml;       END="700 us" ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick, demo or full)" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
echo "== 1/4 mesh ($SPEC)"
"$BRECCIA_BIN/breccia-mesh" "$SPEC" -o "$OUT/specimen.msh" --threads 1
echo "== 2/4 particles"
"$BRECCIA_BIN/breccia-place" "$OUT/specimen.msh" -o "$OUT/particles.h5" --require-groups concrete,charge_hole
if [ ! -x "$BRECCIA_BIN/breccia-solve" ]; then echo "(solver not built: stopping after particles)"; exit 0; fi
echo "== 3/4 solve (end time $END)"
sed "s/^  end: .*/  end: $END/" case.yaml > "$OUT/case.yaml"
"$BRECCIA_BIN/breccia-solve" "$OUT/case.yaml" -o "$OUT/run"
if [ ! -x "$BRECCIA_BIN/breccia-post" ]; then echo "(postproc not built: stopping after solve)"; exit 0; fi
echo "== 4/4 post-process"
"$BRECCIA_BIN/breccia-post" "$OUT/run" --particles "$OUT/particles.h5"
echo "results: $OUT/run (results.xdmf for ParaView), post-processing: $OUT/run/post"
