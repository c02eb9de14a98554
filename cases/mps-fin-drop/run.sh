#!/usr/bin/env bash
# Fin drop at several inclinations (README.md): plastic strain maps, the hinges of the fin,
# the impact force and the energy balance.
#   VARIANT=quick|demo: spacing 3.75 mm (fin 4 particles thick), angles 0 10 20 40
#   VARIANT=full      : spacing 3.75 mm and 1.875 mm
# Defaults: case.yaml's configuration (fin 200 x 15 mm bowed by 0.1 of its thickness, target
# friction 0.2, 15 ms); each of FIN, MU, IMPERFECTION, IMPERFECTION_SHAPE, TIP_RADIUS, END
# changes it at every angle alike.
# ANGLES (optional): the inclinations in degrees. Environment: BRECCIA_BIN, OUT, PYTHON, THREADS.
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
case "$VARIANT" in
  quick|demo|test) SPACINGS=${SPACINGS:-"0.00375"} ;;
  full)            SPACINGS=${SPACINGS:-"0.00375 0.001875"} ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full)" >&2; exit 2 ;;
esac
ANGLES=${ANGLES:-"0 10 20 40"}
# FIN="LENGTH THICKNESS" (m, optional): another fin, e.g. FIN="0.15 0.02" with a spacing of
# a quarter of its thickness (SPACINGS=0.005).
read -r FIN_LENGTH FIN_THICKNESS <<< "${FIN:-0.2 0.015}"
MU=${MU:-0.2}   # friction between the fin and the target (0: frictionless)
# IMPERFECTION=A (a fraction of the fin's thickness), IMPERFECTION_SHAPE=sway|bow: the fin's initial
# out-of-straightness (specimen.py)
IMPERFECTION=${IMPERFECTION:-0.1}
IMPERFECTION_SHAPE=${IMPERFECTION_SHAPE:-bow}
TIP_RADIUS=${TIP_RADIUS:-0}   # the radius of the fin tip's rounded corners (m, specimen.py)
END=${END:-0.015}
mkdir -p "$OUT"
RUNS=()
for dx in $SPACINGS; do
  "$PYTHON" "$HERE/specimen.py" "$OUT/particles_$dx.h5" --spacing "$dx" --fin-length "$FIN_LENGTH" \
    --fin-thickness "$FIN_THICKNESS" --imperfection "$IMPERFECTION" \
    --imperfection-shape "$IMPERFECTION_SHAPE" --tip-radius "$TIP_RADIUS"
  for angle in $ANGLES; do
    name="dx${dx}_angle${angle}"
    # Target normal n = (sin a, cos a): the fin's axis (0, 1) makes the angle a with it; the
    # plane 1 mm below the lowest particle centre along n.
    IFS='|' read -r normal point velocity gravity < <("$PYTHON" -c "
import math, h5py, numpy as np
a = math.radians($angle)
n = np.array([math.sin(a), math.cos(a)])
x = h5py.File('$OUT/particles_$dx.h5', 'r')['particles/position'][:, :2]
q = (np.min(x @ n) - 1e-3) * n
f = lambda v: '[' + ', '.join(f'{c:.9g}' for c in v) + ']'
print('|'.join([f(n), f(q), f(-13.3 * n), f(-9.81 * n)]))")
    every=$("$PYTHON" -c "print(max(1, round($END / (0.3 * $dx / 5900) / 6)))")
    # (with the defaults, the values of case.yaml's variants angle0 ... angle40)
    echo "== $name"
    "$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$OUT/$name" --set "specimen.particles=$OUT/particles_$dx.h5" \
      --set "contact.floor.normal=$normal" --set "contact.floor.point=$point" --set "initial.velocity=$velocity" \
      --set "model.gravity=$gravity" --set "time.end=$END" --set "output.every=$every" \
      --set "contact.floor.static_friction=$MU" --set "contact.floor.kinetic_friction=$MU" \
      --backend cpu --threads "$THREADS" 2>&1 | tail -1
    RUNS+=("$name")
  done
done
"$PYTHON" "$HERE/report.py" "$OUT" "${RUNS[@]}"
echo "report: $OUT/report.json; pictures: $OUT/*.png"
