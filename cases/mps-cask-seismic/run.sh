#!/usr/bin/env bash
# A cask on a shaking floor (README.md): the container's tilt, uplift and sliding with and
# without a gap between canister and container, under a synthetic accelerogram (record.py).
#   VARIANT=quick|demo: canister spacing 0.2 m, gaps 0 and 50 mm, 6 s record
#   VARIANT=full      : spacings 0.2 and 0.1 m (the convergence of the peak tilt), both gaps
# SPACINGS, GAPS (optional): override the lists (e.g. SPACINGS=0.05 GAPS=0.05).
# RECORD=path.csv (optional): any time_s,acceleration_g record instead of the synthetic one.
# PGA, PULSE_PGV, PULSE_PERIOD (optional): the synthetic record's noise peak (g) and its
# near-fault velocity pulse (m/s, s; PULSE_PGV=0: none); record.py and README, "Set-up".
# RESTITUTION=e (optional, 0 < e <= 1): the canister's impacts on the container get a normal
# dashpot with this coefficient of restitution (contact.rigid_bodies[0].restitution; README).
# FLOOR_RESTITUTION=e (optional): the container's corners on the floor get one too
# (contact.rigid_bodies[0].floor_restitution; README).
# END=t (optional): stop the runs at t s of the DURATION-s record (the record is the same).
# HISTORY_EVERY=n (optional): a history row every n steps (case.yaml: 200, i.e. 4.4 ms at 0.2 m).
# SETS="key=value ..." (optional): further --set options for every run (README's studies).
# Environment: BRECCIA_BIN (executables), OUT (output folder), PYTHON, THREADS (optional).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
DURATION=${DURATION:-6}
END=${END:-$DURATION}
case "$VARIANT" in
  quick|demo|test) SPACINGS=${SPACINGS:-"0.2"} ;;
  full)            SPACINGS=${SPACINGS:-"0.2 0.1"} ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|demo|full)" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
if [ -z "${RECORD:-}" ]; then
  RECORD="$OUT/record.csv"
  "$PYTHON" "$HERE/record.py" "$RECORD" --pga "${PGA:-0.9}" --duration "$DURATION" --seed 1995 \
    --pulse-pgv "${PULSE_PGV:-0}" --pulse-period "${PULSE_PERIOD:-1}"
fi
RECORD="$(cd "$(dirname "$RECORD")" && pwd)/$(basename "$RECORD")"
EXTRA=()
[ -n "${RESTITUTION:-}" ] && EXTRA+=(--set "contact.rigid_bodies[0].restitution=$RESTITUTION")
[ -n "${HISTORY_EVERY:-}" ] && EXTRA+=(--set "output.history_every=$HISTORY_EVERY")
[ -n "${FLOOR_RESTITUTION:-}" ] && EXTRA+=(--set "contact.rigid_bodies[0].floor_restitution=$FLOOR_RESTITUTION")
read -r -a SET_LIST <<< "${SETS:-}"   # (split on blanks, no globbing of the [k] in keys)
for kv in "${SET_LIST[@]}"; do EXTRA+=(--set "$kv"); done
RUNS=()
for dx in $SPACINGS; do
  for gap in ${GAPS:-0 0.05}; do
    name="dx${dx}_gap${gap}"
    # Canister particle centres from just above the cavity floor (y = 0.5 m), 4.8 m high, `gap`
    # from the walls at x = +-0.95 m (1e-4 m for "no gap": centres on a wall would start
    # inside it). The spacing is adjusted (by under 3%) so that the columns fit the width.
    read -r h box < <("$PYTHON" -c "
dx, gap = $dx, max($gap, 1e-4)
c = 0.95 - gap
m = round(2 * c / dx); h = 2 * c / m
y0 = 0.5 + 1e-4 - h / 2
print(f'{h:.8g} [{-c - h / 2:.8g}, {y0:.8g}, {c + h / 2:.8g}, {y0 + round(4.8 / h) * h:.8g}]')")
    # (for the standard spacings and gaps, the values of case.yaml's variants of that name)
    echo "== $name"
    "$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$OUT/$name" --set "specimen.bodies.spacing=$h" \
      --set "specimen.bodies.shapes[0].box=$box" --set "contact.floor.motion.history.file=$RECORD" \
      --set "time.end=$END" "${EXTRA[@]}" --backend cpu --threads "$THREADS" 2>&1 | tail -1
    RUNS+=("$name")
  done
done
"$PYTHON" "$HERE/report.py" "$OUT" "$RECORD" "${RUNS[@]}"
echo "report: $OUT/report.json; pictures: $OUT/*.png"
