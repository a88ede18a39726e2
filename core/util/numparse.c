/*
 * numparse.c — fast locale-independent decimal parser (see util/numparse.h).
 *
 * How it works: up to 19 significant digits are accumulated in a uint64 and the decimal
 * exponent is tracked separately. When the significand fits in 15 digits and the exponent is
 * within ±22, both the significand and the power of ten are exact doubles and one IEEE
 * multiplication or division gives the correctly rounded result (Clinger's fast path). Other
 * inputs are scaled in long double (64-bit significand on x86-64), which keeps the result
 * within one double ulp.
 */
#include "util/numparse.h"

#include <math.h>
#include <stdbool.h>
#include <stdint.h>

static const double exact_pow10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                       1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                       1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

static long double scale_pow10(long double v, int e)
{
    static const long double squares[9] = {1e1L,  1e2L,  1e4L,   1e8L,  1e16L,
                                           1e32L, 1e64L, 1e128L, 1e256L};
    bool neg = e < 0;
    unsigned u = (unsigned)(neg ? -e : e);
    long double f = 1.0L;
    for (int i = 0; u && i < 9; i++, u >>= 1)
        if (u & 1)
            f *= squares[i];
    if (u) /* beyond 2^9 − 1: certain overflow or underflow of a double */
        return neg ? 0.0L : HUGE_VALL;
    return neg ? v / f : v * f;
}

const char *affect_parse_double(const char *p, const char *end, double *out)
{
    bool neg = false;
    if (p < end && (*p == '-' || *p == '+')) {
        neg = *p == '-';
        p++;
    }
    uint64_t mant = 0;
    int ndig = 0;     /* significant digits kept in mant */
    int exp10 = 0;    /* decimal exponent adjustment */
    bool any = false; /* saw at least one digit */

    while (p < end && *p >= '0' && *p <= '9') {
        any = true;
        if (ndig < 19) {
            mant = mant * 10 + (uint64_t)(*p - '0');
            if (mant)
                ndig++;
        } else {
            exp10++;
        }
        p++;
    }
    if (p < end && *p == '.') {
        p++;
        while (p < end && *p >= '0' && *p <= '9') {
            any = true;
            if (ndig < 19) {
                mant = mant * 10 + (uint64_t)(*p - '0');
                if (mant)
                    ndig++;
                exp10--;
            }
            p++;
        }
    }
    if (!any)
        return NULL;
    if (p < end && (*p == 'e' || *p == 'E')) {
        p++;
        bool eneg = false;
        if (p < end && (*p == '-' || *p == '+')) {
            eneg = *p == '-';
            p++;
        }
        if (p >= end || *p < '0' || *p > '9')
            return NULL;
        int e = 0;
        while (p < end && *p >= '0' && *p <= '9') {
            if (e < 100000)
                e = e * 10 + (*p - '0');
            p++;
        }
        exp10 += eneg ? -e : e;
    }

    double v;
    if (mant == 0) {
        v = 0.0;
    } else if (ndig <= 15 && exp10 >= -22 && exp10 <= 22) {
        v = (double)mant;
        v = exp10 >= 0 ? v * exact_pow10[exp10] : v / exact_pow10[-exp10];
    } else {
        v = (double)scale_pow10((long double)mant, exp10);
    }
    if (isinf(v))
        return NULL;
    *out = neg ? -v : v;
    return p;
}
