#!/usr/bin/env bash
# version_test.sh BUILD_DIR SOURCE_DIR — one version everywhere: CMakeLists.txt's project
# VERSION, SQL's affect_version() of the built module, the Python package (pyproject.toml and
# sqlite_affect.__version__), and, in a git checkout, any release tag at HEAD (v<version>).
# Tags are made by hand at release (`git tag -a v0.1.0 -m "sqlite-affect 0.1.0"`); a HEAD
# without a v* tag is a development checkout and passes.
set -euo pipefail
build=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
fail() { echo "FAIL: $*" >&2; exit 1; }

version=$(sed -nE 's/^project\(sqlite_affect VERSION ([0-9]+\.[0-9]+\.[0-9]+)[ )].*/\1/p' \
    "$src/CMakeLists.txt")
[ -n "$version" ] || fail "no project(sqlite_affect VERSION x.y.z ...) in CMakeLists.txt"
echo "CMakeLists.txt: $version"

sql=$(sqlite3 :memory: -cmd ".load $build/affect" "SELECT affect_version()" 2>&1 || true)
echo "affect_version(): $sql"
[ "$sql" = "$version" ] || fail "affect_version() is '$sql', the project is $version (rebuild?)"
info=$(sqlite3 :memory: -cmd ".load $build/affect" "SELECT affect_build_info() ->> '\$.version'" \
    2>&1 || true)
[ "$info" = "$version" ] || fail "affect_build_info() version is '$info'"

py=$(sed -nE 's/^__version__ = "([^"]*)"/\1/p' "$src/python/sqlite_affect/__init__.py")
echo "python/sqlite_affect: $py"
[ "$py" = "$version" ] || fail "sqlite_affect.__version__ is '$py', the project is $version"

if git -C "$src" rev-parse --git-dir >/dev/null 2>&1; then
    tags=$(git -C "$src" tag --points-at HEAD --list 'v*')
    if [ -z "$tags" ]; then
        latest=$(git -C "$src" describe --tags --match 'v*' --abbrev=0 2>/dev/null || echo none)
        echo "git: no v* tag at HEAD (development checkout; latest: $latest)"
    else
        for t in $tags; do
            [ "$t" = "v$version" ] || fail "git tag $t at HEAD, but the project version is $version"
        done
        echo "git: tag v$version at HEAD"
    fi
else
    echo "git: not a git checkout"
fi
echo "version: all agree on $version"
