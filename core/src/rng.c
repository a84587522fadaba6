#include "rng.h"

static uint64_t splitmix64(uint64_t *x) { return sylva__mix64(*x += 0x9e3779b97f4a7c15ULL); }

void sylva__rng_seed(sylva__rng *r, uint64_t seed) {
  uint64_t x = seed;
  for (int i = 0; i < 4; i++) r->s[i] = splitmix64(&x);
}

static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

uint64_t sylva__rng_next(sylva__rng *r) {
  uint64_t *s = r->s;
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

double sylva__rng_unit(sylva__rng *r) {
  return (double)(sylva__rng_next(r) >> 11) * 0x1.0p-53;
}

uint32_t sylva__rng_below(sylva__rng *r, uint32_t n) {
  /* Lemire's multiply-shift with rejection: unbiased and deterministic. */
  uint64_t m = (uint64_t)(uint32_t)(sylva__rng_next(r) >> 32) * n;
  uint32_t low = (uint32_t)m;
  if (low < n) {
    uint32_t threshold = (uint32_t)(-n) % n;
    while (low < threshold) {
      m = (uint64_t)(uint32_t)(sylva__rng_next(r) >> 32) * n;
      low = (uint32_t)m;
    }
  }
  return (uint32_t)(m >> 32);
}

void sylva__rng_permutation(sylva__rng *r, int32_t *perm, int32_t n) {
  for (int32_t i = 0; i < n; i++) perm[i] = i;
  for (int32_t i = n - 1; i > 0; i--) {
    int32_t j = (int32_t)sylva__rng_below(r, (uint32_t)i + 1);
    int32_t t = perm[i];
    perm[i] = perm[j];
    perm[j] = t;
  }
}
