#pragma once
// The Sobol' low-discrepancy sequence in up to four dimensions, optionally
// scrambled by a random digital shift: the space-filling design of
// MultiStart (multi_start.h).
//
// Point i is x_j = (XOR of v_{j,k} over the bits k set in gray(i)) / 2^32,
// gray(i) = i ^ (i >> 1), with the direction numbers v_{j,k} = m_{j,k} 2^(32-k)
// of Joe & Kuo (2008, "new-joe-kuo-6.21201"):
//   dimension 1: m = 1, 1, 1, ...      (van der Corput)
//   dimension 2: s = 1, a = 0, m = 1
//   dimension 3: s = 2, a = 1, m = 1, 3
//   dimension 4: s = 3, a = 1, m = 1, 3, 1
// and m_k for k > s from the primitive polynomial's recurrence. The first
// 2^m points form a (t, m, s)-net: each coordinate alone puts exactly one
// point in each interval [k 2^-m, (k+1) 2^-m), and dimensions 1-2 put one in
// each dyadic box of area 2^-m (t = 0).
//
// A digital shift XORs coordinate j of every point with one random 32-bit
// word d_j (from the seed): the points stay a (t, m, s)-net, their first
// point is no longer the origin, and each seed gives another design of the
// same quality. The unshifted sequence is the seed-independent one.

#include <Eigen/Core>
#include <array>
#include <cstdint>

namespace pidlab::optim {

class SobolSequence {
 public:
  static constexpr int kMaxDimensions = 4;
  /// Bits of each coordinate: 2^32 points at most.
  static constexpr int kBits = 32;

  /// `dimensions` in [1, kMaxDimensions] (throws std::invalid_argument
  /// otherwise). Unshifted.
  explicit SobolSequence(int dimensions);
  /// With a random digital shift drawn from `shift_seed` (std::mt19937_64).
  SobolSequence(int dimensions, std::uint64_t shift_seed);

  int dimensions() const { return dimensions_; }
  /// Point `index` (0-based) of the sequence, in [0, 1)^dimensions.
  Eigen::VectorXd Point(std::uint32_t index) const;

 private:
  int dimensions_;
  std::array<std::array<std::uint32_t, kBits>, kMaxDimensions> v_{};
  std::array<std::uint32_t, kMaxDimensions> shift_{};
};

}  // namespace pidlab::optim
