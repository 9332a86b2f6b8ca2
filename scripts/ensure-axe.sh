#!/usr/bin/env bash
# The explorer's browser tests run axe-core (the accessibility checker) in the page. Install
# the pinned release with npm into .venv/axe when it is missing; where npm is absent, stop
# at once with one line saying what to install, so the test is never skipped.
set -euo pipefail
VERSION=4.14.1
PREFIX=${ECDSIM_AXE_PREFIX:-.venv/axe}
AXE="$PREFIX/node_modules/axe-core/axe.min.js"
if [ -f "$AXE" ] && grep -q "\"version\": \"$VERSION\"" "$PREFIX/node_modules/axe-core/package.json"; then
    exit 0
fi
if ! command -v npm >/dev/null 2>&1; then
    echo "error: axe-core is missing and npm is not available: install Debian's 'npm' package, then rerun make test" >&2
    exit 2
fi
echo "installing axe-core $VERSION for the browser tests (npm)..."
mkdir -p "$PREFIX"
npm install --prefix "$PREFIX" --no-audit --no-fund --no-save --silent "axe-core@$VERSION" >/dev/null
if [ ! -f "$AXE" ]; then
    echo "error: npm installed axe-core but $AXE is still missing" >&2
    exit 2
fi
