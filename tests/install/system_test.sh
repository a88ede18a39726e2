#!/usr/bin/env bash
# system_test.sh BUILD_DIR — the default install, as a root user runs it: `cmake --install
# BUILD_DIR` into /usr/local, after which `.load affect` and Python's load_extension('affect')
# work from any directory with no LD_LIBRARY_PATH (the install ran ldconfig, which cached
# "affect.so" through the link libaffect.so; see "install" in CMakeLists.txt).
#
# It must not change this machine: it runs in a private mount namespace (unshare -m) where
# /usr/local is an empty tmpfs and /etc a copy (so ldconfig writes the copy's ld.so.cache).
# Skipped (exit 77) when not root or when unshare/mount are not permitted (containers).
set -euo pipefail
build=$(cd "$1" && pwd)
if [ "$(id -u)" -ne 0 ]; then echo "SKIP: needs root (a mount namespace)"; exit 77; fi
if ! unshare -m --propagation private true 2>/dev/null; then
    echo "SKIP: unshare -m is not permitted here"; exit 77
fi
if ! grep -q '^AFFECT_INSTALL_LDCONFIG:BOOL=ON' "$build/CMakeCache.txt"; then
    echo "SKIP: configured with AFFECT_INSTALL_LDCONFIG=OFF (the install does not run ldconfig)"
    exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cp -a /etc "$tmp/etc" 2>/dev/null || true
[ -f "$tmp/etc/ld.so.conf" ] || { echo "SKIP: could not copy /etc"; exit 77; }
mkdir "$tmp/elsewhere"
version=$(sed -nE 's/^CMAKE_PROJECT_VERSION:STATIC=(.*)/\1/p' "$build/CMakeCache.txt")

unshare -m --propagation private env -u LD_LIBRARY_PATH BUILD="$build" TMPD="$tmp" \
    VERSION="$version" bash -euo pipefail -c '
    mount -t tmpfs tmpfs /usr/local
    mount --bind "$TMPD/etc" /etc
    cmake --install "$BUILD" --prefix /usr/local > "$TMPD/install.log" ||
        { cat "$TMPD/install.log"; exit 1; }
    grep "sqlite-affect" "$TMPD/install.log"
    ldconfig -p | grep -F "affect.so"
    cd "$TMPD/elsewhere"
    got=$(sqlite3 :memory: -cmd ".load affect" "SELECT affect_version()" 2>&1 || true)
    echo "sqlite3 (cwd $PWD): .load affect -> affect_version() = $got"
    [ "$got" = "$VERSION" ] || { echo "FAIL: expected $VERSION"; exit 1; }
    if [ -x /usr/bin/python3 ]; then
        got=$(/usr/bin/python3 -c "
import sqlite3
c = sqlite3.connect(\":memory:\")
c.enable_load_extension(True)
c.load_extension(\"affect\")
print(c.execute(\"SELECT affect_version()\").fetchone()[0])" 2>&1 || true)
        echo "python3: load_extension(\"affect\") -> affect_version() = $got"
        [ "$got" = "$VERSION" ] || { echo "FAIL: expected $VERSION"; exit 1; }
    fi
'
echo "system install: all checks passed"
