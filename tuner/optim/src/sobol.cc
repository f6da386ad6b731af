#include "pidlab/optim/sobol.h"

#include <random>
#include <stdexcept>
#include <string>

namespace pidlab::optim {
namespace {

// One row of Joe & Kuo's table: degree s of the primitive polynomial, its
// inner coefficients a (s - 1 bits, the highest first) and the initial m_k.
struct Primitive {
  int s;
  std::uint32_t a;
  std::array<std::uint32_t, 3> m;
};
constexpr Primitive kJoeKuo[] = {{1, 0, {1, 0, 0}}, {2, 1, {1, 3, 0}}, {3, 1, {1, 3, 1}}};

}  // namespace

SobolSequence::SobolSequence(int dimensions) : dimensions_(dimensions) {
  if (dimensions < 1 || dimensions > kMaxDimensions)
    throw std::invalid_argument("SobolSequence dimensions = " + std::to_string(dimensions) +
                                " must be in [1, " + std::to_string(kMaxDimensions) + "]");
  for (int k = 0; k < kBits; ++k) v_[0][static_cast<std::size_t>(k)] = 1u << (kBits - 1 - k);
  for (int j = 1; j < dimensions; ++j) {
    const Primitive& p = kJoeKuo[j - 1];
    auto& v = v_[static_cast<std::size_t>(j)];
    // v[k] holds v_{k+1} = m_{k+1} 2^(32-(k+1)).
    for (int k = 0; k < p.s; ++k)
      v[static_cast<std::size_t>(k)] = p.m[static_cast<std::size_t>(k)] << (kBits - 1 - k);
    for (int k = p.s; k < kBits; ++k) {
      std::uint32_t x = v[static_cast<std::size_t>(k - p.s)];
      x ^= x >> p.s;
      for (int q = 1; q <= p.s - 1; ++q)
        if ((p.a >> (p.s - 1 - q)) & 1u) x ^= v[static_cast<std::size_t>(k - q)];
      v[static_cast<std::size_t>(k)] = x;
    }
  }
}

SobolSequence::SobolSequence(int dimensions, std::uint64_t shift_seed) : SobolSequence(dimensions) {
  std::mt19937_64 engine(shift_seed);
  for (int j = 0; j < dimensions_; ++j)
    shift_[static_cast<std::size_t>(j)] = static_cast<std::uint32_t>(engine() >> 32);
}

Eigen::VectorXd SobolSequence::Point(std::uint32_t index) const {
  const std::uint32_t gray = index ^ (index >> 1);
  Eigen::VectorXd x(dimensions_);
  for (int j = 0; j < dimensions_; ++j) {
    std::uint32_t bits = shift_[static_cast<std::size_t>(j)];
    for (int k = 0; k < kBits; ++k)
      if ((gray >> k) & 1u) bits ^= v_[static_cast<std::size_t>(j)][static_cast<std::size_t>(k)];
    x[j] = static_cast<double>(bits) * 0x1.0p-32;
  }
  return x;
}

}  // namespace pidlab::optim
