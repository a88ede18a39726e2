/*
 * util/rng.h — a small, fast, seedable pseudo-random generator (xoshiro256**, seeded by
 * splitmix64). No global state: every caller owns its generator, so results depend only on
 * the seed it was given.
 */
#ifndef AFFECT_RNG_H
#define AFFECT_RNG_H

#include <math.h>
#include <stdint.h>

typedef struct affect_rng {
    uint64_t s[4];
} affect_rng;

static inline uint64_t affect_splitmix64(uint64_t *x)
{
    uint64_t z = (*x += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static inline void affect_rng_seed(affect_rng *r, uint64_t seed)
{
    for (int i = 0; i < 4; i++)
        r->s[i] = affect_splitmix64(&seed);
}

static inline uint64_t affect_rng_next(affect_rng *r)
{
    uint64_t *s = r->s;
    uint64_t x = s[1] * 5;
    uint64_t result = ((x << 7) | (x >> 57)) * 9;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = (s[3] << 45) | (s[3] >> 19);
    return result;
}

/* Uniform in [0, 1) with 53 random bits. */
static inline double affect_rng_uniform(affect_rng *r)
{
    return (double)(affect_rng_next(r) >> 11) * 0x1.0p-53;
}

/* Uniform in [lo, hi). */
static inline double affect_rng_range(affect_rng *r, double lo, double hi)
{
    return lo + (hi - lo) * affect_rng_uniform(r);
}

/* Standard normal by the Box–Muller transform (one value per call). */
static inline double affect_rng_normal(affect_rng *r)
{
    double u1 = affect_rng_uniform(r);
    double u2 = affect_rng_uniform(r);
    if (u1 < 1e-300)
        u1 = 1e-300;
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

#endif
