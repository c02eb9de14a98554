#!/usr/bin/env bash
# The 3D slab of glass-branching as a case folder of its own, for the tools that run
# cases/NAME/run.sh with VARIANT=quick|demo|full|test and read OUT/report.json
# (scripts/run_case.sh, tests/cases/check_case.py): `DIM=3d ../run.sh` (see ../run_3d.sh),
# whose report_3d.json is then this case's report.json.
set -euo pipefail
: "${OUT:?output directory}"
DIM=3d bash "$(cd "$(dirname "$0")" && pwd)/../run.sh"
cp "$OUT/report_3d.json" "$OUT/report.json"
