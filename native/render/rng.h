// Random numbers for rendering: a PCG32 generator (O'Neill 2014, "PCG: a
// family of simple fast space-efficient statistically good algorithms") and
// the hash that seeds one independent stream per (seed, pixel, sample), which
// makes an image a pure function of (scene, spp, seed) whatever the thread count.
#pragma once

#include <cstdint>

#include "render/vec.h"

namespace knit::render {

// SplitMix64 finaliser (Steele et al. 2014): a bijective 64-bit mixer.
inline uint64_t mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

inline uint64_t hash_combine(uint64_t a, uint64_t b) { return mix64(a ^ mix64(b)); }

class Pcg32 {
 public:
  Pcg32() { seed(0x853c49e6748fea9bull, 0xda3e39cb94b95bdbull); }
  Pcg32(uint64_t state, uint64_t stream) { seed(state, stream); }

  void seed(uint64_t state, uint64_t stream) {
    state_ = 0;
    inc_ = (stream << 1u) | 1u;
    next_u32();
    state_ += state;
    next_u32();
  }

  uint32_t next_u32() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ull + inc_;
    const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
  }

  // Uniform in [0, 1): the top 24 bits, so the result is exactly representable
  // and never rounds up to 1.
  float next_float() { return static_cast<float>(next_u32() >> 8) * 0x1p-24f; }

 private:
  uint64_t state_ = 0, inc_ = 1;
};

// The sample stream of one camera sample. Dimensions are drawn in order.
class Sampler {
 public:
  Sampler(uint64_t seed, uint64_t pixel_index, uint64_t sample_index)
      : rng_(hash_combine(hash_combine(seed, pixel_index), sample_index),
             hash_combine(seed, 0x6a09e667f3bcc909ull)) {}
  float get1d() { return rng_.next_float(); }
  Vec2 get2d() {
    const float a = rng_.next_float();
    return {a, rng_.next_float()};
  }

 private:
  Pcg32 rng_;
};

}  // namespace knit::render
