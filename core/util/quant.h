/*
 * quant.h — the compact storage of long vectors of doubles (the recognizer's classifier BLOB,
 * version 3: docs/FORMATS.md, "The compact storage"). Two forms, both exact for what they
 * store: a value is first rounded to what the form can hold (affect_q4_round, affect_f24_round),
 * and the rounded values are written and read back to the bit.
 *
 *   4-bit blocks (q4): a vector of n values in blocks of AFFECT_Q4_BLOCK (64; the last may be
 *   shorter); per block a float32 scale s = max |v| / 7 (rounded to float32; 0 for a block of
 *   zeros or of values below FLT_MIN × 7) and per value a signed 4-bit code q in −7 .. 7, the
 *   value being q × s (computed in double: exact). Bytes: 4 × blocks scales, then the codes two
 *   to a byte (the first value in the low nibble; two's complement), ceil(n / 2) bytes; the
 *   unused high nibble of an odd n is 0. Canonical, so that re-encoding gives the same bytes:
 *   a block's scale is 0 (all its codes 0) or a normal float32 with a code of magnitude 7;
 *   the code −8 is never written.
 *
 *   24-bit floats (f24): a finite double rounded to 12 mantissa bits (to nearest, ties to
 *   even; relative error ≤ 2⁻¹³) and stored as the top 3 bytes of its IEEE-754 float64 pattern
 *   (sign, the 11-bit exponent, 12 mantissa bits), little-endian. The full range of float64
 *   stays (the recognizer's normalization scales reach 1e280).
 *
 * Usage:
 *     if (affect_q4_fits(v, n, NULL)) { affect_q4_round(v, n, NULL); affect_q4_write(&w, v, n); }
 *     ... affect_q4_read(&r, v, n, &bad) ...
 */
#ifndef AFFECT_QUANT_H
#define AFFECT_QUANT_H

#include <stdbool.h>
#include <stddef.h>

#include "util/bytes.h"

#define AFFECT_Q4_BLOCK 64u /* values per block of the 4-bit form */
#define AFFECT_Q4_MAX 7     /* largest code magnitude */

/* Bytes of the 4-bit form of n values; false when the size overflows. */
bool affect_q4_size(size_t n, size_t *bytes);

/* Whether every v[i] × factor[i] (factor NULL: 1) is finite and each block's scale fits a
 * float32 (then affect_q4_round succeeds). */
bool affect_q4_fits(const double *v, size_t n, const double *factor);

/* v[i] ← v[i] × factor[i] (factor NULL: 1), then rounded to its 4-bit form, in place. The
 * caller has checked affect_q4_fits. Rounding a rounded vector (factor NULL) changes nothing. */
void affect_q4_round(double *v, size_t n, const double *factor);

/* Writes the 4-bit form of n values that affect_q4_round made (any other value is written as
 * its rounding). */
void affect_q4_write(affect_bw *w, const double *v, size_t n);

/* Reads the 4-bit form of n values into v. false when it is not canonical (above); *bad is
 * then the offset of the offending byte, relative to where the form starts. The caller has
 * checked that affect_q4_size(n) bytes remain. */
bool affect_q4_read(affect_br *r, double *v, size_t n, size_t *bad);

/* v rounded to the 24-bit form (v finite); the result is not finite when v is too close to
 * DBL_MAX to round (the caller refuses it). */
double affect_f24_round(double v);

/* Writes the 24-bit form of a value affect_f24_round made (3 bytes). */
void affect_f24_write(affect_bw *w, double v);

/* Reads a 24-bit value (the caller has checked that 3 bytes remain). */
double affect_f24_read(affect_br *r);

#endif
