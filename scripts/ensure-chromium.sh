#!/usr/bin/env bash
# make test needs Debian's chromium for the explorer's browser tests (no browser download:
# playwright drives /usr/bin/chromium). Install it when it is missing; where that is
# impossible, stop at once with one line naming the package, so the browser tests are
# never skipped and never fail halfway through the suite.
set -euo pipefail
# ECDSIM_CHROMIUM is for this script's own test (tests/test_setup.py); the browser tests use
# /usr/bin/chromium.
CHROMIUM=${ECDSIM_CHROMIUM:-/usr/bin/chromium}
if [ -x "$CHROMIUM" ]; then
    exit 0
fi
if ! command -v apt-get >/dev/null 2>&1; then
    echo "error: $CHROMIUM is missing and apt-get is not available: install Debian's 'chromium' package, then rerun make test" >&2
    exit 2
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
        SUDO="sudo -n"
    else
        echo "error: $CHROMIUM is missing and installing it needs root: run 'sudo apt-get install -y chromium', then rerun make test" >&2
        exit 2
    fi
fi
echo "installing Debian's chromium for the browser tests (apt-get)..."
# CI has no standard input: keep apt from asking anything.
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
if [ ! -x "$CHROMIUM" ]; then
    echo "error: apt-get installed 'chromium' but $CHROMIUM is still missing" >&2
    exit 2
fi
