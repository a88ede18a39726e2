#!/usr/bin/env bash
# install_test.sh BUILD_DIR SOURCE_DIR — `cmake --install` into a temporary prefix, then use what
# it installed from another directory, as a user of that prefix would:
#   1. the files: lib/affect.so (SONAME affect.so) and the link lib/libaffect.so -> affect.so,
#      include/affect/*.h (no internal.h), lib/libsqlite_affect.a, lib/pkgconfig/sqlite-affect.pc
#      naming this prefix and the project's version, share/doc/sqlite-affect/LICENSE;
#   2. `.load affect` in the sqlite3 shell with LD_LIBRARY_PATH=<prefix>/lib (the documented way
#      for a prefix the loader does not search), and Python's conn.load_extension('affect')
#      with Debian's /usr/bin/python3 when present;
#   3. a C program compiled against the installed headers and static library through pkg-config
#      (PKG_CONFIG_PATH=<prefix>/lib/pkgconfig) that builds a motion, encodes and decodes it and
#      reads an HMM configuration, then runs.
set -euo pipefail
build=$(cd "$1" && pwd)
src=$(cd "$2" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix="$tmp/prefix"
fail() { echo "FAIL: $*" >&2; exit 1; }

version=$(sed -nE 's/^project\(sqlite_affect VERSION ([0-9.]+).*/\1/p' "$src/CMakeLists.txt")
[ -n "$version" ] || fail "no project VERSION in $src/CMakeLists.txt"

cmake --install "$build" --prefix "$prefix" > "$tmp/install.log" ||
    { cat "$tmp/install.log"; fail "cmake --install"; }
# the install says how to load from a prefix the loader does not search (as root: "... is not
# searched by the dynamic loader: set LD_LIBRARY_PATH=..."; otherwise "not root ...: set ...")
if grep -q '^AFFECT_INSTALL_LDCONFIG:BOOL=ON' "$build/CMakeCache.txt"; then
    grep -q "set LD_LIBRARY_PATH=$prefix/lib for" "$tmp/install.log" ||
        { cat "$tmp/install.log"; fail "the install does not say how to load from $prefix/lib"; }
fi

lib="$prefix/lib"
[ -f "$lib/affect.so" ] && [ ! -L "$lib/affect.so" ] || fail "$lib/affect.so is not a file"
[ "$(readlink "$lib/libaffect.so")" = affect.so ] ||
    fail "$lib/libaffect.so is not a link to affect.so"
readelf -d "$lib/affect.so" | grep -q 'Library soname: \[affect.so\]' ||
    fail "SONAME is not affect.so"
[ -f "$lib/libsqlite_affect.a" ] || fail "no $lib/libsqlite_affect.a"
[ -f "$prefix/share/doc/sqlite-affect/LICENSE" ] || fail "no LICENSE installed"
for h in "$src"/core/include/affect/*.h; do
    cmp -s "$h" "$prefix/include/affect/$(basename "$h")" ||
        fail "header $(basename "$h") not installed"
done
[ ! -e "$prefix/include/affect/internal.h" ] || fail "internal.h installed"
echo "installed: $(cd "$prefix" && find . -type f -o -type l | sort | tr '\n' ' ')"

export PKG_CONFIG_PATH="$lib/pkgconfig"
[ "$(pkg-config --modversion sqlite-affect)" = "$version" ] ||
    fail "pkg-config version $(pkg-config --modversion sqlite-affect) != $version"
[ "$(pkg-config --variable=prefix sqlite-affect)" = "$prefix" ] || fail "pkg-config prefix"

mkdir "$tmp/elsewhere"
cd "$tmp/elsewhere"
# the shell: a bare name, found through LD_LIBRARY_PATH
got=$(LD_LIBRARY_PATH="$lib" sqlite3 :memory: -cmd ".load affect" "SELECT affect_version()" 2>&1) ||
    fail ".load affect with LD_LIBRARY_PATH: $got"
[ "$got" = "$version" ] || fail "affect_version() = '$got', expected $version"
echo "sqlite3 .load affect (LD_LIBRARY_PATH=$lib): affect_version() = $got"
# (the shell exits with 0 even when -cmd fails, hence the comparisons of its output)
out=$(env -u LD_LIBRARY_PATH sqlite3 :memory: -cmd ".load affect" "SELECT affect_version()" 2>&1 ||
    true)
if [ "$out" = "$version" ]; then
    echo "note: .load affect also works without LD_LIBRARY_PATH here (a system-wide install)"
else
    echo "without LD_LIBRARY_PATH (no system-wide install): $(echo "$out" | head -1)"
fi
if [ -x /usr/bin/python3 ]; then
    got=$(LD_LIBRARY_PATH="$lib" /usr/bin/python3 -c "
import sqlite3
c = sqlite3.connect(':memory:')
c.enable_load_extension(True)
c.load_extension('affect')
print(c.execute('SELECT affect_version()').fetchone()[0])") ||
        fail "python load_extension('affect')"
    [ "$got" = "$version" ] || fail "python: affect_version() = '$got'"
    echo "python3 load_extension('affect'): affect_version() = $got"
fi

# a C user of the core library
cat > use_core.c <<'C'
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <affect/hmm.h>
#include <affect/motion.h>

int main(void)
{
    affect_error err = {0};
    affect_hmm_config cfg;
    affect_hmm_config_default(&cfg);
    affect_motion *m = NULL, *back = NULL, *bad = NULL;
    unsigned char *blob = NULL;
    size_t len = 0;
    int32_t parents[2] = {-1, 0};
    if (affect_motion_create(2, 2, 30.0, &m, &err) != AFFECT_OK ||
        affect_motion_set_name(m, 0, "Hips", 4, &err) != AFFECT_OK ||
        affect_motion_set_name(m, 1, "Head", 4, &err) != AFFECT_OK ||
        affect_motion_set_parents(m, parents, &err) != AFFECT_OK ||
        affect_motion_set_unit(m, "m", &err) != AFFECT_OK) {
        fprintf(stderr, "motion: %s\n", err.msg);
        return 1;
    }
    for (size_t i = 0; i < 2 * 2 * 3; i++)
        m->pos[i] = (float)i * 0.5f;
    if (affect_motion_encode(m, &blob, &len, &err) != AFFECT_OK ||
        affect_motion_decode(blob, len, &back, &err) != AFFECT_OK) {
        fprintf(stderr, "blob: %s\n", err.msg);
        return 1;
    }
    affect_status st = affect_motion_decode(blob, len - 1, &bad, &err);
    printf("decoded %u frames x %u joints (%s, %s), %g fps, unit %s, %zu bytes; "
           "HMM default states %u; truncated BLOB: %s\n",
           back->n_frames, back->n_joints, back->names[0], back->names[1], back->fps, back->unit,
           len, cfg.n_states, st == AFFECT_OK ? "accepted" : err.msg);
    int ok = back->n_frames == 2 && back->n_joints == 2 && strcmp(back->names[1], "Head") == 0
        && back->parents[1] == 0 && back->pos[11] == 5.5f && st != AFFECT_OK && cfg.n_states > 0;
    affect_free(blob);
    affect_motion_free(back);
    affect_motion_free(bad);
    affect_motion_free(m);
    return ok ? 0 : 1;
}
C
cc -std=c11 -Wall -Wextra -Werror use_core.c -o use_core \
    $(pkg-config --cflags sqlite-affect) $(pkg-config --libs sqlite-affect) ||
    fail "cannot build a program against the installed library"
./use_core || fail "the program linked against libsqlite_affect.a failed"
echo "install: all checks passed"
