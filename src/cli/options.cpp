#include "cli/options.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>

#include "unjam/ensemble/force_bounds.hpp"

namespace unjam::cli {
namespace {

std::optional<double> finite_number(const std::string& s) {
  std::string_view v(s);
  if (!v.empty() && v.front() == '+') v.remove_prefix(1);
  double x = 0.0;
  const auto [ptr, ec] = std::from_chars(v.data(), v.data() + v.size(), x);
  if (v.empty() || ec != std::errc() || ptr != v.data() + v.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

}  // namespace

CLI::Validator seed_value() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        std::uint64_t v = 0;
        const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (s.empty() || s.front() == '-' || s.front() == '+' || ec != std::errc() || ptr != s.data() + s.size())
          return "a seed is an integer from 0 to 18446744073709551615, got '" + s + "'";
        return {};
      },
      "SEED");
}

namespace {

// A finite number > 0 (positive) or >= 0.
CLI::Validator finite_number_check(bool positive) {
  const std::string bound = positive ? "> 0" : ">= 0";
  return CLI::Validator(
      [positive, bound](std::string& s) -> std::string {
        const auto v = finite_number(s);
        if (!v || (positive ? !(*v > 0.0) : !(*v >= 0.0))) return "must be a finite number " + bound + ", got '" + s + "'";
        return {};
      },
      "NUMBER " + bound);
}

}  // namespace

CLI::Validator non_negative_number() { return finite_number_check(false); }

CLI::Validator positive_number() { return finite_number_check(true); }

void add_contact_selection_options(CLI::App* cmd, double& gap_tol, double& fn_tol) {
  cmd->add_option("--gap-tol", gap_tol, "touching contacts: gap < gap-tol (R_max)")
      ->capture_default_str()->check(non_negative_number());
  cmd->add_option("--fn-tol", fn_tol, "force-carrying contacts: fn > fn-tol F0")
      ->capture_default_str()->check(non_negative_number());
}

void add_lp_tol_option(CLI::App* cmd, double& lp_tol, const std::string& applies) {
  cmd->add_option("--lp-tol", lp_tol,
                  applies + "CLP's primal and dual feasibility tolerance (docs/ensemble.md, \"The LP's tolerances\")")
      ->capture_default_str()->check(positive_number() & CLI::Range(kMinLpTolerance, kMaxLpTolerance));
}

void add_lp_tolerance_options(CLI::App* cmd, double& lp_tol, double& open_tol) {
  add_lp_tol_option(cmd, lp_tol);
  cmd->add_option("--open-tol", open_tol,
                  "a contact some admissible network loads with fn <= open-tol F0 can open: its fn_min is 0")
      ->capture_default_str()->check(positive_number() & CLI::Range(0.0, kMaxOpenTolF0));
}

}  // namespace unjam::cli
