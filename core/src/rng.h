/* One seeded generator per world: xoshiro256** seeded through splitmix64. */
#ifndef SYLVA_RNG_H
#define SYLVA_RNG_H
#include <stdint.h>

typedef struct sylva__rng {
  uint64_t s[4];
} sylva__rng;

/** The splitmix64 finaliser: a 64-bit word's bits mixed into every bit (the seeding's,
 *  and the world hash's mixing of a node's fields). */
static inline uint64_t sylva__mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

void sylva__rng_seed(sylva__rng *r, uint64_t seed);
uint64_t sylva__rng_next(sylva__rng *r);
/** Uniform in [0, 1) with 53 random bits. */
double sylva__rng_unit(sylva__rng *r);
/** Uniform integer in [0, n), n > 0, without modulo bias. */
uint32_t sylva__rng_below(sylva__rng *r, uint32_t n);
/** A uniform random permutation of 0..n-1 into perm (Fisher-Yates). */
void sylva__rng_permutation(sylva__rng *r, int32_t *perm, int32_t n);
#endif
