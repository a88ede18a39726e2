#!/usr/bin/env bash
# blas_one_thread.sh — every BLAS and LAPACK call of core/ runs inside AFFECT_BLAS(...)
# (core/util/blas.c: OpenBLAS on one thread, so that results do not depend on its thread count).
#   blas_one_thread.sh SOURCE_DIR
# A call is inside when AFFECT_BLAS( is on its line or the line before (clang-format may break
# the line after the macro's parenthesis). Prints every call outside it and fails if there is one.
set -uo pipefail
awk 'FNR == 1 { prev = "" }
     /(cblas|LAPACKE)_[a-z_0-9]+[(]/ && $0 !~ /AFFECT_BLAS[(]/ && prev !~ /AFFECT_BLAS[(]/ {
         print FILENAME ":" FNR ": " $0; bad = 1 }
     { prev = $0 }
     END { exit bad }' "$1"/core/*/*.c
