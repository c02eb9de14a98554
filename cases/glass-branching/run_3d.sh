#!/usr/bin/env bash
# The 3D slab of the glass-branching case (run.sh calls it for VARIANT=3d|3d-quick|3d-test):
# soda-lime glass 100 x 40 x 2 mm (CabanaPD examples/mechanics/inputs/crack_branching.json
# @c89a827; benchmarks.md section 1a), 3D bond-based PMB (nu = 1/4), 2 MPa, G0 = 3.8 J/m2.
#   3d       : dx = 0.25 mm, m = 4 (CabanaPD's 400 x 160 x 8 grid)
#   3d-quick : dx = 1/3 mm, m = 3 (300 x 120 x 6)
#   3d-test  : dx = 0.5 mm, m = 2 (200 x 80 x 4), 28 us: the CTest regression run
# Writes next to the 2D variants' files without touching them: particles_3d.h5, the run
# folder slab3d_sigma2MPa_G3.8, report_3d.json and *_3d*.png.
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
source "$HERE/../../scripts/case_env.sh"
case "$VARIANT" in
  3d)       DX=0.00025;                 DECK=case-3d.yaml ;;
  3d-quick) DX=0.000333333333333333333; DECK=case-3d-quick.yaml ;;
  3d-test)  DX=0.0005;                  DECK=case-3d-quick.yaml; END="28 us" ;;
  *) echo "run_3d.sh: unknown VARIANT '$VARIANT' (3d|3d-quick|3d-test)" >&2; exit 2 ;;
esac
STRESS_MPA=2; G0_J_PER_M2=3.8
mkdir -p "$OUT"
# No-fail strips within delta = 1 mm of the loaded faces y = 0 and y = 40 mm, through the
# whole thickness (add_sets.py boxes are in x-y and take every z).
"$BRECCIA_BIN/breccia-place" --lattice cubic --box 0,0,0,0.1,0.04,0.002 --spacing "$DX" \
  -o "$OUT/particles_3d.h5" > "$OUT/place_3d.log"
"$PYTHON" "$HERE/../../scripts/add_sets.py" "$OUT/particles_3d.h5" \
  no_fail_bottom:0,0,0.1,0.001 no_fail_top:0,0.039,0.1,0.04
name="slab3d_sigma${STRESS_MPA}MPa_G${G0_J_PER_M2}"
mkdir -p "$OUT/$name"
sed -e "s/STRESS/$STRESS_MPA/g" -e "s/fracture_energy: G0 /fracture_energy: $G0_J_PER_M2 /" \
    -e "s#particles: particles.h5#particles: ../particles_3d.h5#" \
    -e "s/no_fail: \[no_fail\]/no_fail: [no_fail_bottom, no_fail_top]/" -e "s/end: 43 us/end: ${END:-43 us}/" \
    "$HERE/$DECK" > "$OUT/$name/case.yaml"
echo "== $name ($VARIANT)"
"$BRECCIA_BIN/breccia-solve" "$OUT/$name/case.yaml" -o "$OUT/$name" --threads "$THREADS" --quiet
"$BRECCIA_BIN/breccia-post" "$OUT/$name" --cracks --fragments --energy --quiet > "$OUT/$name/post.log"
"$PYTHON" "$HERE/report_3d.py" "$OUT" "$name"
echo "report: $OUT/report_3d.json; pictures: $OUT/*_3d*.png"
