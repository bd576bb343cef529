// Random numbers for rendering: a PCG32 generator (O'Neill 2014, "PCG: a
// family of simple fast space-efficient statistically good algorithms"), a
// 64-bit hash, and the sampler of camera samples (scrambled Sobol' points,
// see Sampler), which makes an image a pure function of (scene, spp, seed)
// whatever the thread count.
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

// Bits of x in reverse order.
inline uint32_t reverse_bits(uint32_t x) {
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
  return __builtin_bswap32(x);  // the byte order (GCC and Clang)
}

// The nested uniform (Owen) scramble of a binary fraction, on its bits
// reversed: with x the fraction's bits in reverse order, the scrambled
// fraction's bits in reverse order. Every bit is flipped or kept by a hash
// of the seed and of the bits below it here (above it in the fraction), so
// that a (0, m, 2)-net stays one. The hash is Laine and Karras's (2011),
// with the multipliers of Burley (2020, "Practical hash-based Owen
// scrambling"): adding the seed and x ^= x * c with c even change each bit
// as a function of the bits below it only.
inline uint32_t owen_scramble_reversed(uint32_t x, uint32_t seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}

// The second dimension of Sobol's sequence at index i, as a 32-bit fraction
// with its bits in reverse order: the direction numbers are v_1 = 1/2,
// v_k = v_{k-1} xor (v_{k-1} / 2), here reversed (1, then v xor (v << 1)).
// The first dimension is the van der Corput sequence, whose reversed bits
// are i itself. Together, any 2^m consecutive points aligned on 2^m form a
// (0, m, 2)-net.
inline uint32_t sobol_second_reversed(uint32_t i) {
  uint32_t y = 0, v = 1u;
  for (; i != 0; i >>= 1, v ^= v << 1)
    if (i & 1u) y ^= v;
  return y;
}

// A 32-bit fraction as a float in [0, 1): its top 24 bits, exactly representable.
inline float fraction_to_float(uint32_t x) { return static_cast<float>(x >> 8) * 0x1p-24f; }

// A pseudo-random permutation of [0, 2^bits) (bits 0..32) chosen by four
// 32-bit keys: four rounds of a keyed xor, a multiplication by an odd
// constant and an xorshift to the right, each a bijection of bits-bit
// integers (multiplication carries low bits upwards, the shift high bits
// downwards).
inline uint32_t permute_index(uint32_t x, int bits, uint64_t keys_a, uint64_t keys_b) {
  if (bits <= 0) return 0;
  const uint32_t mask = bits >= 32 ? 0xffffffffu : (1u << bits) - 1u;
  const int shift = bits > 1 ? bits / 2 : 1;
  const uint32_t key[4] = {static_cast<uint32_t>(keys_a), static_cast<uint32_t>(keys_a >> 32),
                           static_cast<uint32_t>(keys_b), static_cast<uint32_t>(keys_b >> 32)};
  const uint32_t mul[4] = {0x9e3779b1u, 0x85ebca77u, 0xc2b2ae3du, 0x27d4eb2fu};
  for (int round = 0; round < 4; ++round) {
    x = ((x ^ key[round]) * mul[round]) & mask;
    x ^= x >> shift;
  }
  return x;
}

// The sample stream of one camera sample: an Owen-scrambled Sobol' (0, 2)-
// sequence per draw, "padded" (Kollig and Keller 2002). Draw d of sample i
// of a pixel (each get1d or get2d call is one draw, in order) takes point
// i of the sequence, with the pixel's sample order permuted and the point
// scrambled by keys hashed from (seed, pixel, d). So the first 2^m samples
// of a pixel are, in every draw on its own, a scrambled (0, m, 2)-net: the
// pixel's jitter, its first light sample, its first bounce... are each
// stratified, far less noisy than independent samples on smooth integrands,
// while draws stay independent of one another (independent permutations of
// the whole block of the pixel's samples: samples_per_pixel rounded up to a
// power of two; 0 = unknown, then the samples are scattered over 2^32 points
// and only the scrambling is left). Each value on its own is uniform on
// [0, 1), so estimates stay unbiased; an image is a pure function of
// (scene, spp, seed), whatever the thread count.
class Sampler {
 public:
  Sampler(uint64_t seed, uint64_t pixel_index, uint64_t sample_index, uint32_t samples_per_pixel = 0)
      : key_(hash_combine(seed, pixel_index)), index_(static_cast<uint32_t>(sample_index)) {
    if (samples_per_pixel > 0)
      while (bits_ < 32 && (uint64_t(1) << bits_) < samples_per_pixel) ++bits_;
    else
      bits_ = 32;
  }
  float get1d() {
    uint32_t i, sx, sy;
    next_draw(i, sx, sy);
    return fraction_to_float(reverse_bits(owen_scramble_reversed(i, sx)));
  }
  // Takes a draw without computing it (the draws after it are unchanged).
  void skip() { ++draw_; }
  Vec2 get2d() {
    uint32_t i, sx, sy;
    next_draw(i, sx, sy);
    return {fraction_to_float(reverse_bits(owen_scramble_reversed(i, sx))),
            fraction_to_float(reverse_bits(owen_scramble_reversed(sobol_second_reversed(i), sy)))};
  }

 private:
  // The next draw's point index and scramble seeds.
  void next_draw(uint32_t& i, uint32_t& sx, uint32_t& sy) {
    const uint64_t a = mix64(key_ + 0x632be59bd9b4e019ull * ++draw_), b = mix64(a), c = mix64(b);
    i = permute_index(index_, bits_, a, b);
    sx = static_cast<uint32_t>(c);
    sy = static_cast<uint32_t>(c >> 32);
  }

  uint64_t key_;
  uint32_t index_;
  int bits_ = 0;  // the pixel's samples are permuted within [0, 2^bits_)
  uint64_t draw_ = 0;
};

}  // namespace knit::render
