/* Seeded pseudo-random numbers (xoshiro256** seeded by splitmix64): every
 * random draw in sasnav goes through here so that runs are reproducible. */
#include "sasnav/scene.h"

#include <math.h>

static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

void sasnav_rng_seed(sasnav_rng *rng, uint64_t seed)
{
    uint64_t st = seed;
    for (int i = 0; i < 4; i++) rng->s[i] = splitmix64(&st);
}

static inline uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

uint64_t sasnav_rng_next(sasnav_rng *rng)
{
    uint64_t *s = rng->s;
    uint64_t result = rotl(s[1] * 5, 7) * 9;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return result;
}

double sasnav_rng_uniform(sasnav_rng *rng)
{
    return (double)(sasnav_rng_next(rng) >> 11) * 0x1.0p-53;
}

double sasnav_rng_normal(sasnav_rng *rng)
{
    /* Box-Muller; the second variate is discarded to keep the state simple. */
    double u1 = sasnav_rng_uniform(rng), u2 = sasnav_rng_uniform(rng);
    if (u1 < 1e-300) u1 = 1e-300;
    return sqrt(-2.0 * log(u1)) * cos(2.0 * M_PI * u2);
}
