#include "unjam/ensemble/friction_threshold.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <string>

#include "unjam/core/error.hpp"
#include "unjam/lp/force_lp.hpp"

namespace unjam {

namespace {

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

// Bisection steps from a bracket of width `width` down to `resolution`.
int steps_to(double width, double resolution) {
  return width > resolution ? static_cast<int>(std::ceil(std::log2(width / resolution))) : 0;
}

}  // namespace

FrictionThreshold friction_threshold(const EquilibriumSystem& system, const FrictionThresholdOptions& options) {
  if (!(options.rel_tol > 0.0 && options.rel_tol < 1.0))
    throw Error("friction threshold: rel_tol must be in (0, 1) (got " + number(options.rel_tol) + ")");
  const bool bracket_given = !std::isnan(options.mu_low) || !std::isnan(options.mu_high);
  if (bracket_given && !(options.mu_low >= 0.0 && options.mu_high > options.mu_low && std::isfinite(options.mu_high)))
    throw Error("friction threshold: a bracket needs 0 <= mu_low < mu_high (got " + number(options.mu_low) +
                ", " + number(options.mu_high) + ")");
  if (options.bracket_checked && !bracket_given)
    throw Error("friction threshold: bracket_checked needs a bracket (mu_low, mu_high)");
  const auto t0 = std::chrono::steady_clock::now();
  FrictionThreshold r;
  r.mu = system.mu;
  r.mu_low = bracket_given ? options.mu_low : 0.0;
  r.mu_high = bracket_given ? options.mu_high : system.mu;
  const double resolution = options.rel_tol * std::max(system.mu, r.mu_high);
  // Two LPs at the ends (none where they are known), then the bisection's.
  const bool ends_known = options.bracket_checked;
  const int total = (ends_known ? 0 : 2) + steps_to(r.mu_high - r.mu_low, resolution);
  EquilibriumSystem at = system;  // the rows do not depend on mu; only the cones change
  // Each LP at mu > 0 starts from the last one's basis (the same columns for every mu > 0); the
  // LP at 0, with one cone column per contact, from scratch, leaving that basis as it was.
  SimplexBasis basis;
  const auto admissible_at = [&](double m) {
    if (options.should_stop && options.should_stop()) throw Cancelled();
    at.mu = m;
    SimplexBasis from_scratch;
    SimplexBasis& start = m > 0.0 ? basis : from_scratch;
    const bool yes = has_admissible_network(at, options.tolerance, start);
    ++r.lps;
    r.iterations += start.iterations;
    return yes;
  };
  const auto report = [&] {
    if (!options.progress) return;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    options.progress(total, r);
  };
  if (!ends_known) {
    if (!admissible_at(r.mu_high))
      throw Error(bracket_given
                      ? "friction threshold: the admissible set is empty at mu_high = " + number(r.mu_high) +
                            ": the threshold lies above it"
                      : "friction threshold: no admissible force network at the packing's own mu = " +
                            number(system.mu) +
                            "; is the packing static and its contact list complete (try a larger --gap-tol)?");
    report();
    if (r.mu_high == 0.0) {
      r.mu_low = 0.0;  // a frictionless system whose set is not empty: mu_s = 0
    } else if (admissible_at(r.mu_low)) {
      if (r.mu_low > 0.0)
        throw Error("friction threshold: the admissible set is not empty at mu_low = " + number(r.mu_low) +
                    ": the threshold lies at or below it");
      r.mu_high = 0.0;  // not empty without friction: mu_s = 0
      report();
    } else {
      report();
    }
  }
  while (r.mu_high - r.mu_low > resolution) {  // none where mu_s = 0
    const double mid = 0.5 * (r.mu_low + r.mu_high);
    (admissible_at(mid) ? r.mu_high : r.mu_low) = mid;
    report();
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace unjam
