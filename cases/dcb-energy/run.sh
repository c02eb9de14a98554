#!/usr/bin/env bash
# Double cantilever beam of glass opened slowly: dissipated energy against G0 x crack area on
# a crack that grows stably (issue 5; README.md). 2D PMB plane stress, lattice dx = 0.1 mm,
# arms 2 mm high (6.6 horizons: see README for why not thinner), pre-crack to 2.037 mm.
#   VARIANT=quick|test: 8 mm long, one rate, 170 us (the run of tests/postproc/test_energy_real_run.cpp)
#   VARIANT=full|demo : 12 mm long, two opening rates, to 300 us / 560 us
# RATES (optional): space-separated "rate_m_s:end" pairs (rate per arm) overriding the defaults.
# STRENGTH (optional, e.g. "30 MPa"): the glass's tensile_strength, so that its bonds soften
#   (docs/theory.md "Quasi-brittle bonds") instead of breaking at the critical stretch.
# Each rate is case.yaml with the rate and end time given as --set (case.yaml's variants long and
# slow are the full runs).
# Environment: BRECCIA_BIN (executables), OUT (output folder), PYTHON, THREADS (optional).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
DX=1e-4
case "$VARIANT" in
  quick|test) LENGTH=8e-3;  RATES=${RATES:-"0.025:170us"} ;;
  full|demo)  LENGTH=12e-3; RATES=${RATES:-"0.025:300us 0.0125:560us"} ;;
  *) echo "run.sh: unknown VARIANT '$VARIANT' (quick|test|full|demo)" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
"$PYTHON" "$HERE/specimen.py" "$OUT/particles.h5" --spacing "$DX" --length "$LENGTH" --arm-height 2e-3 \
  --grip 0.5e-3 > "$OUT/specimen.log"
cat "$OUT/specimen.log"
RUNS=()
for r in $RATES; do  # rate_m_s:end
  IFS=: read -r rate end <<< "$r"
  name="v${rate}"
  options=(--set "boundary[0].value=[0, $rate, 0]" --set "boundary[1].value=[0, -$rate, 0]" --set "time.end=${end/us/ us}")
  [ -z "${STRENGTH:-}" ] || options+=(--set "materials[0].tensile_strength=$STRENGTH")
  echo "== $name"
  "$BRECCIA_BIN/breccia-solve" "$HERE/case.yaml" -o "$OUT/$name" --set "specimen.particles=$OUT/particles.h5" "${options[@]}" \
    --threads "$THREADS" --quiet
  # breccia-post at every output: the crack area and the energy ratio as the crack grows.
  mkdir -p "$OUT/$name/post_steps"
  for step in $("$PYTHON" -c "import h5py, sys; f = h5py.File(sys.argv[1], 'r'); print(' '.join(str(int(g.attrs['step'])) for g in f['output'].values()))" "$OUT/$name/results.h5"); do
    "$BRECCIA_BIN/breccia-post" "$OUT/$name" --step "$step" --cracks --energy --no-plots --quiet \
      > "$OUT/$name/post_steps/post.log" 2>&1 || { cat "$OUT/$name/post_steps/post.log" >&2; exit 3; }
    cp "$OUT/$name/post/post.json" "$OUT/$name/post_steps/$(printf %06d "$step").json"
  done
  RUNS+=("$name")
done
"$PYTHON" "$HERE/report.py" "$OUT" "${RUNS[@]}"
echo "report: $OUT/report.json; pictures: $OUT/*.png"
