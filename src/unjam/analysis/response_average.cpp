#include "unjam/analysis/response_average.hpp"

#include <algorithm>
#include <cmath>

#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/json_integer.hpp"
#include "unjam/packing/csv_table.hpp"

namespace unjam {

namespace {

constexpr const char* kFormat = "unjam-response-average";
constexpr int kVersion = 1;

}  // namespace

ResponseGrid ResponseGrid::for_cell(const Cell& cell, double mean_diameter) {
  const double L_min = std::min(cell.Lx, cell.Ly);
  ResponseGrid g;
  g.h = 0.5 * mean_diameter;
  g.half_width = std::floor(0.5 * L_min / g.h) * g.h;
  g.r_min = 0.5 * mean_diameter;
  g.r_max = 0.5 * L_min;
  g.r_bins = std::max(1, static_cast<int>(std::ceil(10.0 * std::log10(g.r_max / g.r_min))));
  return g;
}

int ResponseGrid::field_side() const { return static_cast<int>(std::lround(2.0 * half_width / h)); }

double ResponseGrid::r_edge(int k) const {
  if (k == 0) return r_min;
  if (k == r_bins) return r_max;
  return r_min * std::pow(r_max / r_min, static_cast<double>(k) / r_bins);
}

void ResponseGrid::validate() const {
  if (!(half_width > 0.0) || !std::isfinite(half_width))
    throw Error("response grid: half_width must be positive and finite");
  if (!(h > 0.0) || !std::isfinite(h)) throw Error("response grid: bin size h must be positive and finite");
  const double n = 2.0 * half_width / h;
  if (n < 0.5 || n > 1e5 || std::abs(n - std::round(n)) > 1e-9 * n)
    throw Error("response grid: 2 half_width / h = " + std::to_string(n) +
                " must be an integer between 1 and 1e5");
  if (!(r_min > 0.0) || !(r_max > r_min) || !std::isfinite(r_max))
    throw Error("response grid: need 0 < r_min < r_max");
  if (r_bins < 1) throw Error("response grid: r_bins must be at least 1");
}

ResponseAverage::ResponseAverage(const ResponseGrid& grid) : grid_(grid) {
  grid_.validate();
  side_ = grid_.field_side();
  for (int k = 0; k <= grid_.r_bins; ++k) r_edges_.push_back(grid_.r_edge(k));
  const std::size_t bins = static_cast<std::size_t>(side_) * side_;
  ux_sum_.assign(bins, FixedPointSum());
  uy_sum_.assign(bins, FixedPointSum());
  count_.assign(bins, 0);
}

int ResponseAverage::profile_bin(double r) const {
  const int K = grid_.r_bins;
  if (!(r >= r_edges_.front() && r < r_edges_.back())) return -1;
  int k = static_cast<int>(K * std::log(r / grid_.r_min) / std::log(grid_.r_max / grid_.r_min));
  k = std::clamp(k, 0, K - 1);
  // The formula can be off by one next to an edge; the stored edges decide.
  while (k > 0 && r < r_edges_[k]) --k;
  while (k < K - 1 && r >= r_edges_[k + 1]) ++k;
  return k;
}

void ResponseAverage::add_probe(std::int64_t id, const FrameField& field, double g) {
  if (has_probe(id)) throw Error("response average: probe " + std::to_string(id) + " added twice");
  if (!(g > 0.0) || !std::isfinite(g)) throw Error("response average: gap g must be positive");
  const std::size_t N = field.size();
  if (field.y.size() != N || field.ux.size() != N || field.uy.size() != N)
    throw Error("response average: frame field arrays differ in length");
  // Check everything first, so that a throw leaves the accumulator unchanged.
  for (std::size_t i = 0; i < N; ++i) {
    const double vx = field.ux[i] / g, vy = field.uy[i] / g;
    if (!std::isfinite(field.x[i]) || !std::isfinite(field.y[i]) ||
        !(std::abs(vx) < FixedPointSum::kMaxAddend) || !(std::abs(vy) < FixedPointSum::kMaxAddend))
      throw Error("response average: probe " + std::to_string(id) + ", grain " + std::to_string(i) +
                  ": position or u/g not finite or |u/g| >= 2^32");
  }
  const double W = grid_.half_width, h = grid_.h;
  ProbeProfile row{std::vector<double>(grid_.r_bins, 0.0), std::vector<std::int64_t>(grid_.r_bins, 0)};
  for (std::size_t i = 0; i < N; ++i) {
    const double x = field.x[i], y = field.y[i];
    const double vx = field.ux[i] / g, vy = field.uy[i] / g;
    const double fx = (x + W) / h, fy = (y + W) / h;
    if (fx >= 0.0 && fx < side_ && fy >= 0.0 && fy < side_) {
      const std::size_t b = index(static_cast<int>(fx), static_cast<int>(fy));
      ux_sum_[b].add(vx);
      uy_sum_[b].add(vy);
      ++count_[b];
    }
    const int k = profile_bin(std::sqrt(x * x + y * y));
    if (k >= 0) {
      row.d_sum[k] += std::sqrt(vx * vx + vy * vy);
      ++row.count[k];
    }
  }
  profiles_.emplace(id, std::move(row));
}

void ResponseAverage::merge(const ResponseAverage& other) {
  if (!(other.grid_ == grid_)) throw Error("response average: cannot merge averages on different grids");
  for (const auto& [id, row] : other.profiles_)
    if (has_probe(id)) throw Error("response average: probe " + std::to_string(id) + " is in both averages");
  for (std::size_t b = 0; b < count_.size(); ++b) {
    ux_sum_[b].add(other.ux_sum_[b]);
    uy_sum_[b].add(other.uy_sum_[b]);
    count_[b] += other.count_[b];
  }
  profiles_.insert(other.profiles_.begin(), other.profiles_.end());
}

Vec2 ResponseAverage::field_mean(int i, int j) const {
  const std::size_t b = index(i, j);
  if (count_[b] == 0) return Vec2::Zero();
  const double c = static_cast<double>(count_[b]);
  return {ux_sum_[b].value() / c, uy_sum_[b].value() / c};
}

RadialProfile ResponseAverage::profile() const {
  const int K = grid_.r_bins;
  const double P = static_cast<double>(profiles_.size());
  RadialProfile p;
  for (int k = 0; k < K; ++k) {
    double S = 0.0;
    std::int64_t C = 0, probes_with = 0;
    for (const auto& [id, row] : profiles_) {  // increasing id: a fixed summation order
      S += row.d_sum[k];
      C += row.count[k];
      probes_with += row.count[k] > 0 ? 1 : 0;
    }
    const double d = C > 0 ? S / static_cast<double>(C) : 0.0;
    double var = 0.0;
    for (const auto& [id, row] : profiles_) {
      const double e = row.d_sum[k] - d * static_cast<double>(row.count[k]);
      var += e * e;
    }
    const double sem = (C > 0 && P >= 2.0) ? std::sqrt(P / (P - 1.0) * var) / static_cast<double>(C) : 0.0;
    p.r_lo.push_back(r_edges_[k]);
    p.r_hi.push_back(r_edges_[k + 1]);
    p.r_mid.push_back(std::sqrt(r_edges_[k] * r_edges_[k + 1]));
    p.d_mean.push_back(d);
    p.d_sem.push_back(sem);
    p.count.push_back(C);
    p.probes.push_back(probes_with);
  }
  return p;
}

std::string ResponseAverage::field_csv() const {
  CsvWriter w({"x", "y", "ux", "uy", "count"});
  const double W = grid_.half_width, h = grid_.h;
  for (int j = 0; j < side_; ++j)
    for (int i = 0; i < side_; ++i) {
      // An empty bin has no mean: NaN.
      const Vec2 u = field_count(i, j) > 0 ? field_mean(i, j) : Vec2::Constant(std::nan(""));
      w.cell(-W + (i + 0.5) * h).cell(-W + (j + 0.5) * h).cell(u.x()).cell(u.y()).cell(field_count(i, j));
      w.end_row();
    }
  return w.str();
}

std::string ResponseAverage::profile_csv() const {
  const RadialProfile p = profile();
  CsvWriter w({"r_lo", "r_hi", "r_mid", "d_mean", "d_sem", "count", "probes"});
  for (std::size_t k = 0; k < p.size(); ++k) {
    const bool empty = p.count[k] == 0;  // no grain in the bin: d and its error are NaN
    w.cell(p.r_lo[k]).cell(p.r_hi[k]).cell(p.r_mid[k]);
    w.cell(empty ? std::nan("") : p.d_mean[k]).cell(empty ? std::nan("") : p.d_sem[k]);
    w.cell(p.count[k]).cell(p.probes[k]);
    w.end_row();
  }
  return w.str();
}

nlohmann::json ResponseAverage::to_json() const {
  using nlohmann::json;
  auto sums = [](const std::vector<FixedPointSum>& s) {
    json a = json::array();
    for (const FixedPointSum& v : s) a.push_back(json::array({v.high(), v.low()}));
    return a;
  };
  json probes = json::array();
  for (const auto& [id, row] : profiles_) probes.push_back({{"id", id}, {"d_sum", row.d_sum}, {"count", row.count}});
  return {{"format", kFormat},
          {"version", kVersion},
          {"grid",
           {{"half_width", grid_.half_width},
            {"h", grid_.h},
            {"r_min", grid_.r_min},
            {"r_max", grid_.r_max},
            {"r_bins", grid_.r_bins}}},
          {"field", {{"ux_sum", sums(ux_sum_)}, {"uy_sum", sums(uy_sum_)}, {"count", count_}}},
          {"probes", std::move(probes)}};
}

ResponseAverage ResponseAverage::from_json(const nlohmann::json& j) {
  try {
    if (j.at("format").get<std::string>() != kFormat || json_integer<int>(j.at("version"), "version") != kVersion)
      throw Error("response average checkpoint: unknown format or version");
    const nlohmann::json& jg = j.at("grid");
    ResponseGrid grid;
    grid.half_width = jg.at("half_width").get<double>();
    grid.h = jg.at("h").get<double>();
    grid.r_min = jg.at("r_min").get<double>();
    grid.r_max = jg.at("r_max").get<double>();
    grid.r_bins = json_integer<int>(jg.at("r_bins"), "r_bins");
    ResponseAverage avg(grid);

    const nlohmann::json& jf = j.at("field");
    const std::size_t bins = avg.count_.size();
    auto read_sums = [&](const nlohmann::json& a, std::vector<FixedPointSum>& out) {
      if (a.size() != bins) throw Error("response average checkpoint: field has the wrong number of bins");
      for (std::size_t b = 0; b < bins; ++b)
        out[b] = FixedPointSum::from_parts(json_integer<std::int64_t>(a.at(b).at(0), "field sum"),
                                           json_integer<std::uint64_t>(a.at(b).at(1), "field sum"));
    };
    read_sums(jf.at("ux_sum"), avg.ux_sum_);
    read_sums(jf.at("uy_sum"), avg.uy_sum_);
    avg.count_ = json_integers<std::int64_t>(jf.at("count"), "field count");
    if (avg.count_.size() != bins) throw Error("response average checkpoint: field has the wrong number of bins");

    for (const nlohmann::json& jp : j.at("probes")) {
      const std::int64_t id = json_integer<std::int64_t>(jp.at("id"), "probe id");
      ProbeProfile row{jp.at("d_sum").get<std::vector<double>>(), json_integers<std::int64_t>(jp.at("count"), "probe count")};
      if (row.d_sum.size() != static_cast<std::size_t>(grid.r_bins) || row.count.size() != row.d_sum.size())
        throw Error("response average checkpoint: probe " + std::to_string(id) + " has the wrong number of bins");
      if (!avg.profiles_.emplace(id, std::move(row)).second)
        throw Error("response average checkpoint: probe " + std::to_string(id) + " listed twice");
    }
    return avg;
  } catch (const nlohmann::json::exception& e) {
    throw Error(std::string("response average checkpoint: ") + e.what());
  }
}

void ResponseAverage::save(const std::filesystem::path& path) const {
  write_file_atomic(path, to_json().dump() + "\n");
}

ResponseAverage ResponseAverage::load(const std::filesystem::path& path) {
  const std::string text = read_file(path);
  try {
    return from_json(nlohmann::json::parse(text));
  } catch (const nlohmann::json::exception& e) {
    throw Error(path.string() + ": " + e.what());
  } catch (const Error& e) {
    throw Error(path.string() + ": " + e.what());
  }
}

}  // namespace unjam
