#!/usr/bin/env bash
# The explorer's browser tests run axe-core (the accessibility checker) in the page. Install
# the pinned release with npm into .venv/axe when it is missing; where npm is absent, install
# Debian's npm (root or password-less sudo), else stop at once with one line saying what to
# install, so the test is never skipped.
set -euo pipefail
# This script's folder, without dirname (its test runs it with bash alone on the PATH).
case "${BASH_SOURCE[0]}" in */*) HERE=${BASH_SOURCE[0]%/*} ;; *) HERE=. ;; esac
VERSION=4.14.1
PREFIX=${ECDSIM_AXE_PREFIX:-.venv/axe}
AXE="$PREFIX/node_modules/axe-core/axe.min.js"
if [ -f "$AXE" ] && grep -q "\"version\": \"$VERSION\"" "$PREFIX/node_modules/axe-core/package.json"; then
    exit 0
fi
# ECDSIM_NPM is for this script's own test (tests/test_setup.py).
NPM=${ECDSIM_NPM:-npm}
if ! command -v "$NPM" >/dev/null 2>&1; then
    # As for chromium: install Debian's npm where we may (root or password-less sudo).
    bash "$HERE/apt-install.sh" "axe-core's installer npm" npm
    if ! command -v "$NPM" >/dev/null 2>&1; then
        echo "error: apt-get installed 'npm' but $NPM is still missing" >&2
        exit 2
    fi
fi
echo "installing axe-core $VERSION for the browser tests (npm)..."
mkdir -p "$PREFIX"
"$NPM" install --prefix "$PREFIX" --no-audit --no-fund --no-save --silent "axe-core@$VERSION" >/dev/null
if [ ! -f "$AXE" ]; then
    echo "error: npm installed axe-core but $AXE is still missing" >&2
    exit 2
fi
