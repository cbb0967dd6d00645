#pragma once
// Integers read from JSON with a check instead of a cast: nlohmann's get<integer type>() of a
// floating-point number converts it with a cast, undefined behaviour outside the type's
// range (e.g. 1e300 as std::int64_t), and silently wraps integers that do not fit.
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "unjam/core/error.hpp"

namespace unjam {

// The value of `v` as T if it is an integer in T's range: a JSON integer, or a floating-point
// number with an integral value (as tools that store every number as a double write them).
// Throws unjam::Error("<what> must be an integer in [min, max], found <v>") otherwise.
template <typename T>
T json_integer(const nlohmann::json& v, const std::string& what) {
  static_assert(std::is_integral_v<T> && !std::is_same_v<T, bool>);
  using limits = std::numeric_limits<T>;
  if (v.is_number_unsigned()) {
    if (std::in_range<T>(v.get<std::uint64_t>())) return static_cast<T>(v.get<std::uint64_t>());
  } else if (v.is_number_integer()) {
    if (std::in_range<T>(v.get<std::int64_t>())) return static_cast<T>(v.get<std::int64_t>());
  } else if (v.is_number_float()) {
    // T's range as doubles: [min, 2^(bits - 1)) for signed T, [0, 2^bits) for unsigned T;
    // both bounds are exact powers of two.
    const double d = v.get<double>();
    const double upper = 2.0 * static_cast<double>(limits::max() / 2 + 1);
    if (d == std::trunc(d) && d >= static_cast<double>(limits::min()) && d < upper) return static_cast<T>(d);
  }
  throw Error(what + " must be an integer in [" + std::to_string(limits::min()) + ", " +
              std::to_string(limits::max()) + "], found " + v.dump());
}

// Every element of the JSON array `v` as json_integer<T>; throws unjam::Error if `v` is not an array.
template <typename T>
std::vector<T> json_integers(const nlohmann::json& v, const std::string& what) {
  if (!v.is_array()) throw Error(what + " must be an array of integers, found " + v.type_name());
  std::vector<T> out;
  out.reserve(v.size());
  for (const nlohmann::json& x : v) out.push_back(json_integer<T>(x, what));
  return out;
}

}  // namespace unjam
