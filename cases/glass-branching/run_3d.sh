#!/usr/bin/env bash
# The 3D slab of the glass-branching case (run.sh calls it for VARIANT=3d|3d-quick|3d-test):
# soda-lime glass 100 x 40 x 2 mm (CabanaPD examples/mechanics/inputs/crack_branching.json
# @c89a827; benchmarks.md section 1a), 3D bond-based PMB (nu = 1/4), 2 MPa, G0 = 3.8 J/m2.
#   3d       : dx = 0.25 mm, m = 4 (CabanaPD's 400 x 160 x 8 grid): case-3d.yaml
#   3d-quick : dx = 1/3 mm, m = 3 (300 x 120 x 6): case-3d-quick.yaml
#   3d-test  : dx = 0.5 mm, m = 2 (200 x 80 x 4), 28 us: the CTest regression run,
#              case-3d-quick.yaml's variant `test`
# Writes next to the 2D variants' files without touching them: particles_3d.h5, the run
# folder slab3d_sigma2MPa_G3.8, report_3d.json and *_3d*.png.
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
OPTIONS=()
case "$VARIANT" in
  3d)       DX=0.00025;                 DECK=case-3d.yaml ;;
  3d-quick) DX=0.000333333333333333333; DECK=case-3d-quick.yaml ;;
  3d-test)  DX=0.0005;                  DECK=case-3d-quick.yaml; OPTIONS=(--variant test) ;;
  *) echo "run_3d.sh: unknown VARIANT '$VARIANT' (3d|3d-quick|3d-test)" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
# The slab (the case file names its no-fail strips within delta of the loaded faces).
"$BRECCIA_BIN/breccia-place" --lattice cubic --box 0,0,0,0.1,0.04,0.002 --spacing "$DX" \
  -o "$OUT/particles_3d.h5" > "$OUT/place_3d.log"
name="slab3d_sigma2MPa_G3.8"
echo "== $name ($VARIANT)"
"$BRECCIA_BIN/breccia-solve" "$HERE/$DECK" -o "$OUT/$name" --set "specimen.particles=$OUT/particles_3d.h5" "${OPTIONS[@]}" \
  --threads "$THREADS" --quiet
"$BRECCIA_BIN/breccia-post" "$OUT/$name" --cracks --fragments --energy --quiet > "$OUT/$name/post.log"
"$PYTHON" "$HERE/report_3d.py" "$OUT" "$name"
echo "report: $OUT/report_3d.json; pictures: $OUT/*_3d*.png"
