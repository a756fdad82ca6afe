// SPDX-License-Identifier: Apache-2.0
#include "render/sampler.h"

#include <boost/random/sobol.hpp>

#include <vector>

namespace envpis::render {

namespace sobol {

const std::uint32_t* matrix(int dim) {
  // Boost generates in Gray-code order: after seed(2^(k+1) - 2) the next point is the one whose Gray
  // code is 2^k, i.e. column k of every dimension's generator matrix.
  static const std::vector<std::uint32_t> columns = [] {
    std::vector<std::uint32_t> c(static_cast<std::size_t>(kDimensions) * 32);
    boost::random::sobol_engine<std::uint32_t, 32> engine(kDimensions);
    for (int k = 0; k < 32; ++k) {
      engine.seed(static_cast<std::uint32_t>((std::uint64_t(1) << (k + 1)) - 2));
      for (int d = 0; d < kDimensions; ++d) c[static_cast<std::size_t>(d) * 32 + k] = engine();
    }
    return c;
  }();
  return &columns[static_cast<std::size_t>(dim) * 32];
}

const std::uint32_t* nibble_tables(int dim) {
  static const std::vector<std::uint32_t> tables = [] {
    std::vector<std::uint32_t> t(static_cast<std::size_t>(kDimensions) * 128);
    for (int d = 0; d < kDimensions; ++d) {
      const std::uint32_t* v = matrix(d);
      for (int g = 0; g < 8; ++g)
        for (std::uint32_t j = 0; j < 16; ++j) {
          std::uint32_t x = 0;
          for (int b = 0; b < 4; ++b)
            if (j & (1u << b)) x ^= v[4 * g + b];
          t[static_cast<std::size_t>(d) * 128 + 16 * g + j] = reverse_bits(x);
        }
    }
    return t;
  }();
  return &tables[static_cast<std::size_t>(dim) * 128];
}

}  // namespace sobol

SamplerKind parse_sampler(const std::string& s) {
  if (s == "sobol") return SamplerKind::Sobol;
  if (s == "independent") return SamplerKind::Independent;
  if (s == "padded") return SamplerKind::Padded;
  throw Error("unknown sampler '" + s + "' (expected sobol, padded or independent)");
}

const char* to_string(SamplerKind k) {
  switch (k) {
    case SamplerKind::Sobol: return "sobol";
    case SamplerKind::Padded: return "padded";
    case SamplerKind::Independent: break;
  }
  return "independent";
}

}  // namespace envpis::render
