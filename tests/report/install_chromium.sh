#!/usr/bin/env bash
# Install Debian's chromium for the report's real-browser test (tests/report).
# Safe to call repeatedly: does nothing when chromium is already on PATH, and never fails
# the caller (the browser test skips with a reason when chromium is absent).
set -u
if command -v chromium >/dev/null 2>&1; then
    echo "chromium already installed: $(command -v chromium)"
    exit 0
fi
if [ "$(id -u)" != "0" ] || ! command -v apt-get >/dev/null 2>&1; then
    echo "cannot install chromium (needs root and apt-get); the browser test will be skipped"
    exit 0
fi
export DEBIAN_FRONTEND=noninteractive
if apt-get update -qq && apt-get install -y -qq chromium >/dev/null; then
    echo "installed $(chromium --version 2>/dev/null)"
else
    echo "chromium could not be installed; the browser test will be skipped"
fi
exit 0
