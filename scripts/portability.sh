#!/usr/bin/env bash
# The portability matrix (docs/reproducibility.md): the test suite under the numerical
# set-ups of other machines, so that a result tied to this CPU shows up here first.
#
#   NUMBA_CPU_NAME=generic      compiled kernels built for a baseline x86-64 CPU (no AVX,
#                               no FMA), as on a machine older or other than this one
#   OPENBLAS_CORETYPE=Prescott  OpenBLAS's SSE3 kernels (another summation order in every
#                               matrix product, solve and SVD)
#   OPENBLAS_CORETYPE=Haswell   its AVX2 kernels (those an AMD EPYC runs; skipped on a CPU
#                               without AVX2, where they would not run)
#   OPENBLAS_NUM_THREADS=1      one BLAS thread (another blocking of large products)
#
# Usage: scripts/portability.sh [pytest arguments]   (default: the whole suite)
# e.g.   scripts/portability.sh tests/test_examples_fixed.py -x
# Each run's output goes to $PORTABILITY_LOGS (default .portability/NAME.log); the last
# lines printed are one verdict per set-up and the exit status is 1 if any run failed.
# Each set-up runs `ecdsim precompile` first: NUMBA_CPU_NAME=generic compiles every kernel
# again once (about 25 s of CPU), cached beside the others.
set -u
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-.venv/bin/python}
LOGS=${PORTABILITY_LOGS:-.portability}
mkdir -p "$LOGS"

SETUPS=(
    "NUMBA_CPU_NAME=generic"
    "OPENBLAS_CORETYPE=Prescott"
    "OPENBLAS_CORETYPE=Haswell"
    "OPENBLAS_NUM_THREADS=1"
)

has_avx2() {
    grep -qw avx2 /proc/cpuinfo 2>/dev/null
}

declare -a verdicts
status=0
for setup in "${SETUPS[@]}"; do
    name=${setup//[=]/-}
    if [[ $setup == OPENBLAS_CORETYPE=Haswell ]] && ! has_avx2; then
        verdicts+=("skipped  $setup (this CPU has no AVX2)")
        continue
    fi
    log="$LOGS/$name.log"
    echo "== $setup: $PYTHON -m pytest -p no:cacheprovider $* (log: $log)"
    # The kernels of this set-up compiled first (generic: a cold cache), so that no timed
    # test waits for a compilation.
    env "$setup" "$PYTHON" -m ecdsim precompile >"$log" 2>&1 &&
        env "$setup" "$PYTHON" -m pytest -p no:cacheprovider "$@" >>"$log" 2>&1
    code=$?
    summary=$(tail -n 1 "$log")
    if [[ $code -eq 0 ]]; then
        verdicts+=("passed   $setup: $summary")
    else
        status=1
        verdicts+=("FAILED   $setup: $summary")
        grep -E '^(FAILED|ERROR) ' "$log" | sed 's/^/           /'
    fi
done
echo "== portability matrix"
printf '%s\n' "${verdicts[@]}"
exit $status
