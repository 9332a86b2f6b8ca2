#!/usr/bin/env bash
# Install Debian packages for make test, or stop at once with one line saying what to do.
# Usage: apt-install.sh WHAT PACKAGE...   (WHAT names what is missing, for the messages)
# Shared by ensure-chromium.sh and ensure-axe.sh: apt-get as root or with password-less
# sudo, no questions asked (CI has no standard input).
set -euo pipefail
WHAT=$1
shift
PACKAGES="$*"
if ! command -v apt-get >/dev/null 2>&1; then
    echo "error: $WHAT is missing and apt-get is not available: install Debian's '$PACKAGES' package, then rerun make test" >&2
    exit 2
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
        SUDO="sudo -n"
    else
        echo "error: $WHAT is missing and installing it needs root: run 'sudo apt-get install -y $PACKAGES', then rerun make test" >&2
        exit 2
    fi
fi
echo "installing Debian's $PACKAGES for make test (apt-get)..."
# shellcheck disable=SC2086 # one word per package
if ! { $SUDO apt-get update -qq && $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $PACKAGES >/dev/null; }; then
    echo "error: apt-get could not install '$PACKAGES' (its messages above): install it, then rerun make test" >&2
    exit 2
fi
