// SPDX-License-Identifier: Apache-2.0
// Owen-scrambled Sobol points in one and two dimensions, with hash-based nested uniform scrambling
// (Burley 2020, "Practical Hash-based Owen Scrambling"; the Laine-Karras style hash with the
// constants of Vegdahl 2021).
//
// The full sequence serves the first kDimensions dimensions; past them, pairs are "padded": the first
// two Sobol dimensions (a (0,2)-sequence in base 2: any aligned 2^m points are a (0,m,2)-net) with
// their own scramble and index shuffle per pair. The shuffle maps each aligned block of 2^m indices
// onto an aligned block of 2^m indices, so prefixes of 2^m samples stay nets.
#pragma once

#include <cstdint>

namespace envpis::render::sobol {

/// Dimensions of the full (not padded) Sobol sequence: Joe and Kuo's direction numbers, read from
/// Boost.Random's sobol_engine.
constexpr int kDimensions = 64;

/// The 32 direction numbers (generator matrix columns) of dimension `dim` < kDimensions: bit k of the
/// index contributes column k.
const std::uint32_t* matrix(int dim);

/// Per dimension, 8 tables of 16 entries (the dimensions' tables one after the other, 128 entries
/// each): entry j of table g is the XOR of the columns 4g .. 4g + 3
/// selected by the bits of j, bit-reversed (the scramble works on reversed bits, so the points are
/// read reversed, which saves a reversal per number). The renderer's indices are shuffled (full
/// 32-bit words), so a bit-by-bit loop costs 32 steps and about 16 mispredicted branches per
/// dimension; this is 8 loads and XORs. 32 KB in all, of which a direct-lighting sample touches a
/// handful of dimensions (512 bytes each).
const std::uint32_t* nibble_tables(int dim);

inline std::uint32_t reverse_bits(std::uint32_t x) {
  x = __builtin_bswap32(x);
  x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  return ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
}

/// The point of `index` from one dimension's tables (nibble_tables(dim)), its bits reversed.
inline std::uint32_t sample_dim_reversed(const std::uint32_t* t, std::uint32_t index) {
  std::uint32_t result = 0;
  for (int g = 0; g < 8; ++g, index >>= 4) result ^= t[16 * g + (index & 15u)];
  return result;
}

/// Point `index` of dimension `dim` < kDimensions: the XOR of the columns selected by the index's bits.
inline std::uint32_t sample_dim(std::uint32_t index, int dim) {
  return reverse_bits(sample_dim_reversed(nibble_tables(dim), index));
}

/// A bijection of 32-bit words in which every output bit depends only on the input bits at the same
/// or lower positions (additions, odd multiplications and x ^= x * even carry upwards only).
inline std::uint32_t laine_karras_permutation(std::uint32_t x, std::uint32_t seed) {
  x ^= x * 0x3d20adeau;
  x += seed;
  x *= (seed >> 16) | 1u;
  x ^= x * 0x05526c56u;
  x ^= x * 0x53a22864u;
  return x;
}

/// Nested uniform scramble of a 32-bit fixed-point number in [0, 1): each bit is flipped by a hash of
/// the bits above it (more significant), which is Owen's scrambling.
inline std::uint32_t nested_uniform_scramble(std::uint32_t x, std::uint32_t seed) {
  return reverse_bits(laine_karras_permutation(reverse_bits(x), seed));
}

/// nested_uniform_scramble(sample_dim(index, dim), seed), with one bit reversal instead of three;
/// `t` is nibble_tables(dim).
inline std::uint32_t scrambled_dim(const std::uint32_t* t, std::uint32_t index, std::uint32_t seed) {
  return reverse_bits(laine_karras_permutation(sample_dim_reversed(t, index), seed));
}

/// 24 high bits as a float in [0, 1) (never rounds up to 1).
inline float to_unit_float(std::uint32_t x) { return float(x >> 8) * 0x1p-24f; }

/// Seeds of one padded pair (or single dimension): the index shuffle and one scramble per axis.
struct Scramble {
  std::uint32_t shuffle, x, y;
};

inline float sample_1d(std::uint32_t index, const Scramble& s) {
  const std::uint32_t i = nested_uniform_scramble(index, s.shuffle);
  return to_unit_float(scrambled_dim(nibble_tables(0), i, s.x));
}

inline void sample_2d(std::uint32_t index, const Scramble& s, float* u, float* v) {
  const std::uint32_t i = nested_uniform_scramble(index, s.shuffle);
  *u = to_unit_float(scrambled_dim(nibble_tables(0), i, s.x));
  *v = to_unit_float(scrambled_dim(nibble_tables(1), i, s.y));
}

}  // namespace envpis::render::sobol
