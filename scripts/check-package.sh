#!/usr/bin/env bash
# The .deb checked from its own files alone (make check-package; CI runs it after the tests):
#   scripts/check-package.sh [BUILD_DIR]      (default: build)
# 1. builds breccia_<version>_<arch>.deb with CPack in BUILD_DIR (cmake --build --target package);
# 2. unpacks it with dpkg -x into an empty temporary folder (no root, nothing installed);
# 3. checks the layout and that no executable names the source or build tree (strings);
# 4. with the working directory in that folder, PATH = the unpacked usr/bin then the system's,
#    and no BRECCIA_* / LD_* variables, runs breccia-plan on a small lattice case and the quick
#    concrete-blast demo (breccia-run-case: mesh, place, solve, post), and checks their outputs.
# KEEP=1 leaves the temporary folder for inspection. Exit 0 when every check passes.
set -euo pipefail
SRC="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="$(cd "${1:-build}" && pwd)"
THREADS=${THREADS:-2}
fail() { echo "check-package: FAIL: $*" >&2; exit 1; }

start=$SECONDS
echo "== 1/4 package (cpack in $BUILD)"
rm -f "$BUILD"/breccia_*.deb
cmake --build "$BUILD" --target package
DEB=$(ls "$BUILD"/breccia_*.deb 2>/dev/null | head -1)
[ -f "$DEB" ] || fail "no breccia_*.deb in $BUILD after cpack"
dpkg-deb --field "$DEB" Package Version Architecture Maintainer Depends Recommends
echo "($(du -h "$DEB" | cut -f1), $((SECONDS - start)) s)"

echo "== 2/4 unpack"
WORK=$(mktemp -d "${TMPDIR:-/tmp}/breccia-package.XXXXXX")
if [ -z "${KEEP:-}" ]; then trap 'rm -rf "$WORK"' EXIT; else echo "(kept: $WORK)"; fi
case "$WORK/" in "$SRC"/*|"$BUILD"/*) fail "the temporary folder $WORK is inside the source or build tree";; esac
dpkg -x "$DEB" "$WORK/root"
P="$WORK/root/usr"

echo "== 3/4 layout, and no source or build path in the executables"
TOOLS="breccia-mesh breccia-place breccia-solve breccia-mps breccia-post breccia-plan breccia-atlas breccia-run-case"
for t in $TOOLS; do [ -x "$P/bin/$t" ] || fail "usr/bin/$t missing or not executable"; done
for f in share/breccia/cases/concrete-blast/run.sh share/breccia/scripts/case_env.sh \
         share/breccia/postproc/scripts/plot_energy.py share/breccia/plan/throughputs.yaml \
         share/breccia/plan/atlas.csv share/doc/breccia/README.md share/doc/breccia/architecture.md; do
  [ -f "$P/$f" ] || fail "usr/$f missing"
done
for t in $TOOLS; do
  if strings -a "$P/bin/$t" | grep -n -F -e "$SRC" -e "$BUILD"; then
    fail "usr/bin/$t names the source or build tree (above): data must be found from the executable's location"
  fi
done
echo "ok: $(ls "$P/bin" | wc -l) programs, $(find "$WORK/root" -type f | wc -l) files, no $SRC or $BUILD inside"

echo "== 4/4 run from the unpacked files alone (cwd $WORK)"
cd "$WORK"
# A clean environment: only the unpacked tools and the system's programs (bash, python3).
run() { env -i HOME="$WORK" PATH="$P/bin:/usr/bin:/bin" LANG=C.UTF-8 THREADS="$THREADS" OMP_NUM_THREADS="$THREADS" "$@"; }
[ "$(run sh -c 'command -v breccia-solve')" = "$P/bin/breccia-solve" ] || fail "breccia-solve does not resolve to the unpacked tree"

# breccia-plan with its default data (share/breccia/plan): a 2D PMB bar, a second of work.
cat > plan_case.yaml <<'EOF'
specimen: {lattice: {dimension: 2, box: [0, 0, 0.1, 0.03], spacing: 0.4 mm, thickness: 1 mm}}
model: {type: pmb, planar: plane_strain, horizon_factor: 3.015}
materials: [{name: rock, density: 2600, youngs_modulus: 50 GPa, poisson_ratio: 0.25}]
initial: [{type: velocity, set: xmin, value: [1, 0, 0]}]
time: {end: 20 us}
output: {results: false}
EOF
run breccia-plan plan_case.yaml --tolerance 0.05 --write plan_proposed.yaml > plan.log 2>&1 \
  || { cat plan.log; fail "breccia-plan failed"; }
[ -s plan_proposed.yaml ] || { cat plan.log; fail "breccia-plan wrote no proposal"; }
echo "ok: breccia-plan (throughputs and atlas from usr/share/breccia/plan)"

demo_start=$SECONDS
run breccia-run-case concrete-blast quick "$WORK/out" || fail "breccia-run-case concrete-blast quick failed"
demo_s=$((SECONDS - demo_start))
for f in specimen.msh particles.h5 run/results.h5 run/summary.json run/history.csv run/post/post.json; do
  [ -s "$WORK/out/$f" ] || fail "demo output $f missing or empty"
done
# The charts come from the installed scripts: breccia-post records any that failed in post.json.
run python3 - "$WORK/out/run/post" <<'EOF' || fail "post-processing charts"
import json, pathlib, sys
post = pathlib.Path(sys.argv[1])
failures = json.load(open(post / "post.json")).get("plot_failures", [])
pngs = sorted(p.name for p in post.glob("*.png"))
if failures or not pngs:
    sys.exit(f"plot failures {failures}, charts {pngs}")
print("ok: charts", ", ".join(pngs))
EOF
echo "check-package: OK ($DEB; demo $demo_s s, total $((SECONDS - start)) s)"
