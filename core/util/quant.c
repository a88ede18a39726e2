/*
 * quant.c — the compact storage of long vectors (util/quant.h): 4-bit codes in blocks of 64
 * with a float32 scale per block, and 24-bit floats (float64 rounded to 12 mantissa bits).
 *
 * Usage: see util/quant.h. Rounding happens once, where the model is made (the recognizer's
 * training); writing and reading then move exactly those values, so a decoded model is the
 * trained one to the bit and re-encodes to the same bytes.
 */
#include "util/quant.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

bool affect_q4_size(size_t n, size_t *bytes)
{
    size_t blocks = n / AFFECT_Q4_BLOCK + (n % AFFECT_Q4_BLOCK != 0), scales;
    return affect_mul_size(blocks, 4, &scales) && affect_add_size(scales, n / 2 + n % 2, bytes);
}

/* The block's largest magnitude after the factors (NaN when a product is not finite). */
static double block_max(const double *v, size_t n, const double *factor)
{
    double a = 0.0;
    for (size_t i = 0; i < n; i++) {
        double x = factor ? v[i] * factor[i] : v[i];
        if (!isfinite(x))
            return NAN;
        if (fabs(x) > a)
            a = fabs(x);
    }
    return a;
}

/* The float32 scale of a block whose largest magnitude is a (0: the block is stored as 0). */
static float block_scale(double a)
{
    float s = (float)(a / AFFECT_Q4_MAX);
    return s >= FLT_MIN ? s : 0.0f;
}

bool affect_q4_fits(const double *v, size_t n, const double *factor)
{
    for (size_t b = 0; b < n; b += AFFECT_Q4_BLOCK) {
        size_t len = n - b < AFFECT_Q4_BLOCK ? n - b : AFFECT_Q4_BLOCK;
        double a = block_max(v + b, len, factor ? factor + b : NULL);
        if (!(a / AFFECT_Q4_MAX <= FLT_MAX))
            return false;
    }
    return true;
}

/* The code of x in a block of scale s > 0. */
static int code_of(double x, float s)
{
    double q = nearbyint(x / s);
    return q > AFFECT_Q4_MAX ? AFFECT_Q4_MAX : q < -AFFECT_Q4_MAX ? -AFFECT_Q4_MAX : (int)q;
}

void affect_q4_round(double *v, size_t n, const double *factor)
{
    for (size_t b = 0; b < n; b += AFFECT_Q4_BLOCK) {
        size_t len = n - b < AFFECT_Q4_BLOCK ? n - b : AFFECT_Q4_BLOCK;
        double *x = v + b;
        if (factor)
            for (size_t i = 0; i < len; i++)
                x[i] *= factor[b + i];
        float s = block_scale(block_max(x, len, NULL));
        for (size_t i = 0; i < len; i++)
            x[i] = s > 0 ? code_of(x[i], s) * (double)s : 0.0;
    }
}

void affect_q4_write(affect_bw *w, const double *v, size_t n)
{
    unsigned char buf[AFFECT_Q4_BLOCK / 2];
    for (size_t b = 0; b < n; b += AFFECT_Q4_BLOCK) { /* the scales */
        size_t len = n - b < AFFECT_Q4_BLOCK ? n - b : AFFECT_Q4_BLOCK;
        float s = block_scale(block_max(v + b, len, NULL));
        uint32_t u;
        memcpy(&u, &s, sizeof u);
        affect_bw_u32(w, u);
    }
    for (size_t b = 0; b < n; b += AFFECT_Q4_BLOCK) { /* the codes */
        size_t len = n - b < AFFECT_Q4_BLOCK ? n - b : AFFECT_Q4_BLOCK;
        float s = block_scale(block_max(v + b, len, NULL));
        memset(buf, 0, sizeof buf);
        for (size_t i = 0; i < len; i++) {
            unsigned code = s > 0 ? (unsigned)code_of(v[b + i], s) & 15u : 0u;
            buf[i / 2] |= (unsigned char)(code << (4 * (i % 2)));
        }
        affect_bw_bytes(w, buf, len / 2 + len % 2);
    }
}

bool affect_q4_read(affect_br *r, double *v, size_t n, size_t *bad)
{
    size_t blocks = n / AFFECT_Q4_BLOCK + (n % AFFECT_Q4_BLOCK != 0);
    const unsigned char *sc, *codes;
    affect_br_bytes(r, &sc, blocks * 4);
    affect_br_bytes(r, &codes, n / 2 + n % 2);
    size_t codes_off = blocks * 4;
    for (size_t k = 0; k < blocks; k++) {
        uint32_t u = (uint32_t)sc[4 * k] | (uint32_t)sc[4 * k + 1] << 8 |
                     (uint32_t)sc[4 * k + 2] << 16 | (uint32_t)sc[4 * k + 3] << 24;
        float s;
        memcpy(&s, &u, sizeof s);
        size_t b = k * AFFECT_Q4_BLOCK, len = n - b < AFFECT_Q4_BLOCK ? n - b : AFFECT_Q4_BLOCK;
        if (u != 0 && !(s >= FLT_MIN && s <= FLT_MAX)) {
            *bad = 4 * k; /* negative, subnormal, infinite or NaN */
            return false;
        }
        int top = 0;
        for (size_t i = 0; i < len; i++) {
            size_t j = b + i;
            int code = codes[j / 2] >> (4 * (j % 2)) & 15;
            if (code >= 8)
                code -= 16;
            if (code == -8 || (u == 0 && code != 0)) {
                *bad = codes_off + j / 2;
                return false;
            }
            if (abs(code) > top)
                top = abs(code);
            v[j] = code * (double)s;
        }
        if (u != 0 && top != AFFECT_Q4_MAX) {
            *bad = 4 * k; /* a scale larger than its block needs */
            return false;
        }
    }
    if (n % 2 && codes[n / 2] >> 4) {
        *bad = codes_off + n / 2;
        return false;
    }
    return true;
}

double affect_f24_round(double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    const uint64_t low = ((uint64_t)1 << 40) - 1, half = (uint64_t)1 << 39;
    uint64_t rest = u & low;
    u &= ~low;
    if (rest > half || (rest == half && (u >> 40 & 1)))
        u += (uint64_t)1 << 40; /* a carry into the exponent is the right rounding */
    double out;
    memcpy(&out, &u, sizeof out);
    return out;
}

void affect_f24_write(affect_bw *w, double v)
{
    uint64_t u;
    v = affect_f24_round(v);
    memcpy(&u, &v, sizeof u);
    unsigned char b[3] = {(unsigned char)(u >> 40), (unsigned char)(u >> 48),
                          (unsigned char)(u >> 56)};
    affect_bw_bytes(w, b, 3);
}

double affect_f24_read(affect_br *r)
{
    const unsigned char *b;
    affect_br_bytes(r, &b, 3);
    uint64_t u = (uint64_t)b[0] << 40 | (uint64_t)b[1] << 48 | (uint64_t)b[2] << 56;
    double v;
    memcpy(&v, &u, sizeof v);
    return v;
}
