#!/usr/bin/env bash
# make test needs Debian's chromium for the explorer's browser tests (no browser download:
# playwright drives /usr/bin/chromium). Install it when it is missing; where that is
# impossible, stop at once with one line naming the package, so the browser tests are
# never skipped and never fail halfway through the suite.
set -euo pipefail
# This script's folder, without dirname (its test runs it with bash alone on the PATH).
case "${BASH_SOURCE[0]}" in */*) HERE=${BASH_SOURCE[0]%/*} ;; *) HERE=. ;; esac
# ECDSIM_CHROMIUM is for this script's own test (tests/test_setup.py); the browser tests use
# /usr/bin/chromium.
CHROMIUM=${ECDSIM_CHROMIUM:-/usr/bin/chromium}
if [ -x "$CHROMIUM" ]; then
    exit 0
fi
bash "$HERE/apt-install.sh" "$CHROMIUM" chromium
if [ ! -x "$CHROMIUM" ]; then
    echo "error: apt-get installed 'chromium' but $CHROMIUM is still missing" >&2
    exit 2
fi
