#!/usr/bin/env bash
# The explorer's browser tests run axe-core (the accessibility checker) in the page. Install
# the pinned release with npm into .venv/axe when it is missing; where npm is absent, install
# Debian's npm (root or password-less sudo), else stop at once with one line saying what to
# install, so the test is never skipped.
set -euo pipefail
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
    if ! command -v apt-get >/dev/null 2>&1; then
        echo "error: axe-core is missing and npm is not available (nor apt-get): install Debian's 'npm' package, then rerun make test" >&2
        exit 2
    fi
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then
        if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
            SUDO="sudo -n"
        else
            echo "error: axe-core is missing and installing npm needs root: run 'sudo apt-get install -y npm', then rerun make test" >&2
            exit 2
        fi
    fi
    echo "installing Debian's npm for the browser tests' axe-core (apt-get)..."
    $SUDO apt-get update -qq
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq npm >/dev/null
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
