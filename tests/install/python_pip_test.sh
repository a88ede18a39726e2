#!/usr/bin/env bash
# python_pip_test.sh BUILD_DIR SOURCE_DIR [PYTHON] — the Python package as a user installs it,
# offline: a venv of Debian's python3 that sees the system's packages (NumPy, setuptools, wheel:
# `python3 -m venv --system-site-packages`; Debian 12's own pip refuses to install into the
# system Python without --break-system-packages), then
#     venv/bin/pip install --no-build-isolation --no-index SOURCE_DIR/python
# and the package's tests run by the venv's Python from another directory, with the package
# imported from the venv (not from the checkout) and the module given by SQLITE_AFFECT_PATH.
# Skipped (77) when the venv module or setuptools is missing (apt-get install python3-venv
# python3-setuptools python3-wheel).
set -euo pipefail
build=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
py=${3:-/usr/bin/python3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$py" -c "import venv, ensurepip, setuptools, wheel" 2>/dev/null ||
    { echo "SKIP: $py lacks venv/ensurepip/setuptools/wheel" \
           "(apt-get install python3-venv python3-setuptools python3-wheel)"; exit 77; }
"$py" -m venv --system-site-packages "$tmp/venv"
# the package is built in a copy: setuptools writes build/ and *.egg-info next to the sources
cp -r "$src/python" "$tmp/python"
rm -f "$tmp/python/sqlite_affect/"*.so
PIP_NO_INPUT=1 PIP_DISABLE_PIP_VERSION_CHECK=1 "$tmp/venv/bin/pip" install -q \
    --no-build-isolation --no-index "$tmp/python"
cd "$tmp"
where=$(env -u PYTHONPATH "$tmp/venv/bin/python" -c \
    "import sqlite_affect; print(sqlite_affect.__file__, sqlite_affect.__version__)")
echo "installed: $where"
case "$where" in "$tmp/venv/"*) ;; *) echo "FAIL: not imported from the venv"; exit 1 ;; esac
env -u PYTHONPATH SQLITE_AFFECT_PATH="$build/affect.so" "$tmp/venv/bin/python" \
    "$src/python/tests/test_sqlite_affect.py" "$src/tests/fixtures"
