#!/usr/bin/env bash
# The peak tilt over an ensemble of records that differ from the case's by PERTURB of its peak
# (record.py --perturb; README, "An ensemble over perturbed records"): run.sh once per member
# seed, then ensemble.py prints each run's mean, standard deviation and range of the peak tilt.
#   MEMBERS="1 2 3 ..." (seeds of the perturbation; default 1-10), PERTURB (default 0.001),
#   SPACINGS, GAPS, END, DURATION, PGA, PULSE_PGV, PULSE_PERIOD as for run.sh (the pulse is the
#   same in every member: the perturbation is in the noise).
# Environment: BRECCIA_BIN, OUT, PYTHON, THREADS (as run.sh).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
MEMBERS=${MEMBERS:-"1 2 3 4 5 6 7 8 9 10"}
PERTURB=${PERTURB:-0.001}
mkdir -p "$OUT"
for s in $MEMBERS; do
  m="$OUT/m$s"
  mkdir -p "$m"
  "$PYTHON" "$HERE/record.py" "$m/record.csv" --pga "${PGA:-0.9}" --duration "${DURATION:-6}" --seed 1995 \
    --perturb "$PERTURB" --perturb-seed "$s" --pulse-pgv "${PULSE_PGV:-0}" --pulse-period "${PULSE_PERIOD:-1}" > /dev/null
  RECORD="$m/record.csv" OUT="$m" bash "$HERE/run.sh" | grep -v '^report:'
done
"$PYTHON" "$HERE/ensemble.py" "$OUT"
