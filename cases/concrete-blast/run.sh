#!/usr/bin/env bash
# Concrete block with a charge hole, end to end: spec -> mesh -> particles -> PD -> post -> measures.
# Environment (scripts/run_case.sh): BRECCIA_BIN, OUT, VARIANT (quick|demo|mid|full), PYTHON.
# PEAKS="1000 300 100" (MPa): the pressure study instead of one run: the same case with the
# closed-cavity peak pressure scaled, one run each, a row each in $OUT/study.csv.
# END_TIME="500 us": end the runs there instead of the case's time.end (a shorter study).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
PYTHON=${PYTHON:-/usr/bin/python3}
case "$VARIANT" in
  quick) SPEC=specimen-quick.yaml; OPTIONS=(--variant quick) ;;  # to 150 us
  demo)  SPEC=specimen-demo.yaml;  OPTIONS=() ;;                   # case.yaml as shipped: to 1000 us
  mid)   SPEC=specimen-mid.yaml;   OPTIONS=() ;;
  full)  SPEC=specimen.yaml;       OPTIONS=() ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick, demo, mid or full)" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
echo "== 1/4 mesh ($SPEC)"
"$BRECCIA_BIN/breccia-mesh" "$HERE/$SPEC" -o "$OUT/specimen.msh" --threads 1
echo "== 2/4 particles"
"$BRECCIA_BIN/breccia-place" "$OUT/specimen.msh" -o "$OUT/particles.h5" --require-groups concrete,charge_hole
if [ ! -x "$BRECCIA_BIN/breccia-solve" ]; then echo "(solver not built: stopping after particles)"; exit 0; fi

# One run: case.yaml (the variant of $VARIANT) with the peak (MPa; empty: as written) in folder $1.
one_run() {
  local dir="$1" peak="${2:-}"
  echo "== 3/4 solve ($VARIANT${peak:+, closed-cavity peak $peak MPa})"
  "$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$dir" --set "specimen.particles=$OUT/particles.h5" "${OPTIONS[@]}" \
    ${peak:+--set "loads[0].history.peak=$peak MPa"} ${END_TIME:+--set "time.end=$END_TIME"}
  if [ ! -x "$BRECCIA_BIN/breccia-post" ]; then echo "(postproc not built: stopping after solve)"; return 0; fi
  echo "== 4/4 post-process"
  "$BRECCIA_BIN/breccia-post" "$dir" --particles "$OUT/particles.h5"
  # The issue's measures (large pieces, debris, radial cracks): every variant but a single quick
  # run; the pressure study (PEAKS) reads them from each run, quick included.
  if [ "$VARIANT" != quick ] || [ -n "${PEAKS:-}" ]; then
    "$PYTHON" "$HERE/measures.py" "$dir" "$OUT/particles.h5" --label "$VARIANT${peak:+ $peak MPa}" --json "$dir/measures.json"
  fi
}

if [ -n "${PEAKS:-}" ]; then
  for p in $PEAKS; do one_run "$OUT/peak_$p" "$p"; done
  "$PYTHON" - "$OUT" $PEAKS <<'PY'
import csv, json, sys
out, peaks = sys.argv[1], sys.argv[2:]
keys = ["large_pieces", "large_mass_share", "largest_share", "debris_share_under_1g", "radial_cracks_ring",
        "radial_cracks_side_faces", "side_face_damaged_share", "fragments"]
# From history.csv: the wall's peak gauge pressure and its time, when the gas vented, the gas
# work, the external work and the energy balance (kinetic + strain + dissipated - external) at the end.
extra = ["wall_peak_MPa", "wall_peak_us", "vent_us", "gas_work_J", "external_work_J", "energy_balance_J"]
with open(f"{out}/study.csv", "w") as f:
    f.write("peak_MPa," + ",".join(keys + extra) + "\n")
    for p in peaks:
        m = json.load(open(f"{out}/peak_{p}/measures.json"))
        h = list(csv.DictReader(open(f"{out}/peak_{p}/history.csv")))
        top = max(h, key=lambda r: float(r["gas_pressure_Pa"]))
        vent = next((float(r["time_s"]) * 1e6 for r in h if r["gas_vented"] == "1"), float("nan"))
        e = [float(top["gas_pressure_Pa"]) / 1e6, float(top["time_s"]) * 1e6, vent,
             float(h[-1]["gas_work_J"]), float(h[-1]["external_work_J"]), float(h[-1]["total_J"])]
        f.write(p + "," + ",".join(str(m[k]) for k in keys) + "," + ",".join(f"{v:.4g}" for v in e) + "\n")
print(open(f"{out}/study.csv").read())
PY
else
  one_run "$OUT/run"
  echo "results: $OUT/run (results.xdmf for ParaView), post-processing: $OUT/run/post"
fi
