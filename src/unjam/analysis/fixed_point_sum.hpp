#pragma once
// A sum of doubles that does not depend on the order or grouping of its terms: every addend
// v is rounded to the nearest multiple of 2^-56 (~1.4e-17) and the multiples are summed as a
// 128-bit integer. Integer addition is associative, so accumulators filled in any order and
// merged in any grouping hold bit-identical totals (what ResponseAverage::merge needs to
// combine probes run in parallel threads deterministically).
//
// Range: |v| < 2^32 (~4.3e9) per addend; then at least 2^39 (~5e11) addends fit before the
// 128-bit total could overflow. value() is the total rounded to the nearest double.
// Uses the GCC/Clang extension __int128.
#include <cmath>
#include <cstdint>
#include <string>

#include "unjam/core/error.hpp"

namespace unjam {

class FixedPointSum {
 public:
  static constexpr int kFractionBits = 56;
  static constexpr double kMaxAddend = 4294967296.0;  // 2^32

  // Adds v; throws unjam::Error if v is not finite or |v| >= 2^32.
  void add(double v) {
    if (!(std::abs(v) < kMaxAddend))
      throw Error("FixedPointSum: addend " + std::to_string(v) + " is not finite or exceeds 2^32");
    q_ += static_cast<Int128>(std::round(std::ldexp(v, kFractionBits)));
  }
  void add(const FixedPointSum& other) { q_ += other.q_; }

  double value() const { return std::ldexp(static_cast<double>(q_), -kFractionBits); }

  // The 128-bit integer as (high, low) 64-bit halves, for checkpoints: q = hi * 2^64 + lo.
  std::int64_t high() const { return static_cast<std::int64_t>(q_ >> 64); }
  std::uint64_t low() const { return static_cast<std::uint64_t>(q_); }
  static FixedPointSum from_parts(std::int64_t high, std::uint64_t low) {
    FixedPointSum s;
    s.q_ = static_cast<Int128>(static_cast<UInt128>(static_cast<Int128>(high)) << 64 | low);
    return s;
  }

  bool operator==(const FixedPointSum&) const = default;

 private:
  __extension__ typedef __int128 Int128;
  __extension__ typedef unsigned __int128 UInt128;
  Int128 q_ = 0;
};

}  // namespace unjam
