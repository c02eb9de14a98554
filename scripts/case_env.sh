# Environment every cases/*/run.sh shares (sourced, not run): the executables and output
# folder must be given (scripts/run_case.sh or tests/cases set them); the rest has defaults.
: "${BRECCIA_BIN:?path to the Breccia executables}" "${OUT:?output directory}"
VARIANT=${VARIANT:-quick}
PYTHON=${PYTHON:-/usr/bin/python3}
THREADS=${THREADS:-$(nproc)}
