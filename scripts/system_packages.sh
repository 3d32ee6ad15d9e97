#!/usr/bin/env bash
# Debian packages that mvtk uses when they are present, installed by `make report` and
# `make test` (never required: without them mvtk runs, slower or with tests skipped).
#
#   report  libopenblas0-pthread: an optimised BLAS for CHOLMOD. The sksparse-minimal
#           wheel bundles the reference BLAS; mvtk loads the system OpenBLAS before it
#           (mvtk._blas.load_system_blas), which makes the sparse factorisation 2-3x
#           faster (docs/guide/performance.md).
#   test    the above, plus chromium (the report's real-browser test) and libblas3 /
#           liblapack3 (OpenSeesPy, the peer of the FE benchmark tests).
#
# Installs with apt-get when run as root on Debian/Ubuntu; otherwise prints the command
# to run and carries on.
set -uo pipefail
want=(libopenblas0-pthread)
if [ "${1:-report}" = "test" ]; then
    want+=(chromium libblas3 liblapack3)
fi
missing=()
for pkg in "${want[@]}"; do
    if command -v dpkg-query >/dev/null 2>&1; then
        dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
    fi
done
if ! command -v dpkg-query >/dev/null 2>&1; then
    echo "system packages: not a Debian system; for a 2-3x faster sparse factorisation install OpenBLAS (mvtk finds libopenblas with the dynamic loader)"
    exit 0
fi
[ ${#missing[@]} -eq 0 ] && exit 0
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    echo "system packages: installing ${missing[*]}"
    if ! (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null); then
        echo "system packages: could not install ${missing[*]}; mvtk runs without them (slower factorisation, some tests skipped)"
    fi
else
    echo "system packages: ${missing[*]} missing; mvtk runs without them (slower factorisation, some tests skipped). To install: sudo apt-get install ${missing[*]}"
fi
exit 0
