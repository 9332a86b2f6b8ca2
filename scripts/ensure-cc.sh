#!/usr/bin/env bash
# make test needs a C compiler: ecdsim export-fmu compiles the damper FMU with the system's
# cc, and tests/test_fmu.py exports and runs such FMUs. Install Debian's gcc when no compiler
# is found (as ensure-chromium.sh installs chromium); where that is impossible, stop at once
# with one line naming the package, so the FMU tests never fail halfway through the suite.
set -euo pipefail
# This script's folder, without dirname (its test runs it with bash alone on the PATH).
case "${BASH_SOURCE[0]}" in */*) HERE=${BASH_SOURCE[0]%/*} ;; *) HERE=. ;; esac
found() {
    [ -n "${CC:-}" ] || command -v cc >/dev/null 2>&1 || command -v gcc >/dev/null 2>&1 ||
        command -v clang >/dev/null 2>&1
}
if found; then
    exit 0
fi
bash "$HERE/apt-install.sh" "a C compiler (cc)" gcc
if ! found; then
    echo "error: apt-get installed 'gcc' but no C compiler (cc, gcc) is on the PATH" >&2
    exit 2
fi
