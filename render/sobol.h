// Owen-scrambled Sobol points in one and two dimensions, with hash-based nested uniform scrambling
// (Burley 2020, "Practical Hash-based Owen Scrambling"; the Laine-Karras style hash with the
// constants of Vegdahl 2021).
//
// Only the first two Sobol dimensions are used: together they form a (0,2)-sequence in base 2, so any
// 2^m consecutive points starting at a multiple of 2^m are a (0,m,2)-net (one point in every
// elementary interval of area 2^-m). Higher dimensions are "padded": each pair of dimensions gets its
// own scramble and its own shuffle of the sample index, which decorrelates the pairs while keeping
// every pair stratified (the shuffle maps each aligned block of 2^m indices onto an aligned block of
// 2^m indices, so prefixes of 2^m samples stay nets).
#pragma once

#include <cstdint>

namespace envpis::render::sobol {

inline std::uint32_t reverse_bits(std::uint32_t x) {
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
  x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
  return (x >> 16) | (x << 16);
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

/// Sobol dimension 0 (the van der Corput sequence) of point `index`, as 32-bit fixed point.
inline std::uint32_t sobol_dim0(std::uint32_t index) { return reverse_bits(index); }

/// Sobol dimension 1 of point `index`: all its direction numbers m_k are 1, so the generator matrix is
/// Pascal's triangle mod 2 and each column is the previous one xor itself shifted right by one.
inline std::uint32_t sobol_dim1(std::uint32_t index) {
  std::uint32_t result = 0;
  for (std::uint32_t v = 1u << 31; index != 0; index >>= 1, v ^= v >> 1)
    if (index & 1u) result ^= v;
  return result;
}

/// 24 high bits as a float in [0, 1) (never rounds up to 1).
inline float to_unit_float(std::uint32_t x) { return float(x >> 8) * 0x1p-24f; }

/// Seeds of one padded pair (or single dimension): the index shuffle and one scramble per axis.
struct Scramble {
  std::uint32_t shuffle, x, y;
};

inline float sample_1d(std::uint32_t index, const Scramble& s) {
  const std::uint32_t i = nested_uniform_scramble(index, s.shuffle);
  return to_unit_float(nested_uniform_scramble(sobol_dim0(i), s.x));
}

inline void sample_2d(std::uint32_t index, const Scramble& s, float* u, float* v) {
  const std::uint32_t i = nested_uniform_scramble(index, s.shuffle);
  *u = to_unit_float(nested_uniform_scramble(sobol_dim0(i), s.x));
  *v = to_unit_float(nested_uniform_scramble(sobol_dim1(i), s.y));
}

}  // namespace envpis::render::sobol
