// libFuzzer target of the LP runs' checkpoint readers: BoundsCheckpoint (`unjam bounds` and
// unjam.bounds resume from it) and ThresholdCheckpoint (`unjam threshold`), on the fixture
// p50-mu0.1 (81 force-carrying contacts). An input is a checkpoint file's text; both readers
// read it (each against its own run's settings). Every input must end in unjam::Error or in a
// resumed state the run could have saved: for the bounds, 81 values each, minima NaN (not known
// yet) or >= 0, every value NaN or finite, counts in range, a valid record of the runs' time;
// for the threshold, 0 <= mu_low < mu_high <= mu and counts in range. Saved again, it must read
// back unchanged. An input that is a JSON object without "settings" is also read as an edit of
// the saved checkpoints (its keys replace theirs). A crash, a sanitizer report, a timeout or
// another exception fails.
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "fuzz_common.hpp"
#include "unjam/campaign/bounds_checkpoint.hpp"
#include "unjam/campaign/threshold_checkpoint.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/packing_io.hpp"

namespace {

namespace fs = std::filesystem;
using unjam::fuzz::accepted_invalid;

constexpr int kContacts = 81;
constexpr double kMu = 0.1;

const unjam::Packing& packing() {
  static const unjam::Packing p = unjam::read_packing(fs::path(UNJAM_FIXTURES_DIR) / "p50-mu0.1");
  return p;
}

const nlohmann::json& bounds_settings() {
  static const nlohmann::json s =
      unjam::bounds_checkpoint_settings("p50-mu0.1", packing(), 1e-9, 1e-9, unjam::ForceBoundsOptions{}, "", kContacts);
  return s;
}

const nlohmann::json& threshold_settings() {
  static const nlohmann::json s = unjam::threshold_checkpoint_settings(packing(), 1e-9, 1e-9, kContacts, kMu, 1e-3);
  return s;
}

// The checkpoints' files: on tmpfs where there is one (the readers' writability check and the
// saves flush to disk), in a directory of this process made for each input and removed after it.
// A run that found a failure ends without removing its directory; the directories of runs no
// longer alive are removed when the next run starts.
const fs::path& work_dir() {
  static const fs::path dir = [] {
    const fs::path root = fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
    const std::string prefix = "unjam_fuzz_lp_checkpoint_";
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator(root, ec)) {
      const std::string name = e.path().filename().string();
      if (name.rfind(prefix, 0) != 0) continue;
      const std::string digits = name.substr(prefix.size());
      if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
      if (::kill(static_cast<pid_t>(std::stol(digits)), 0) != 0 && errno == ESRCH) fs::remove_all(e.path(), ec);
    }
    return root / (prefix + std::to_string(::getpid()));
  }();
  return dir;
}

// The checkpoints a run saves, each a seed: bounds with nothing known yet, and with a few values
// known, every count set and a record of two runs; a threshold's bracket after its two ends,
// and after a few bisections.
std::vector<std::string> saved_checkpoints() {
  const fs::path dir = work_dir();
  fs::create_directories(dir);
  std::vector<std::string> out;
  // Bounds: nothing known yet; a few values known with every count set and a record of two runs.
  unjam::ForceBounds b;
  b.fn_min = b.fn_max = Eigen::VectorXd::Constant(kContacts, std::nan(""));
  const fs::path bf = dir / "seed_bounds.json";
  fs::remove(bf);
  unjam::BoundsCheckpoint(bf, bounds_settings()).save(b, {});
  out.push_back(unjam::read_file(bf));
  b.fn_min[0] = 0.0;
  b.fn_min[5] = 0.125;
  b.fn_max[5] = 2.5;
  b.fn_max[80] = 1.0e-3;
  b.min_lps_skipped = 1;
  b.iterations = 1234;
  b.loosened_solves = 2;
  b.simplex_finishes = 3;
  b.unscaled_solves = 1;
  unjam::CampaignTime runs;
  runs.runs = 2;
  runs.wall_seconds = 12.5;
  runs.busy_seconds = 11.0;
  runs.untimed = 1;
  unjam::BoundsCheckpoint(bf, bounds_settings()).save(b, runs);
  out.push_back(unjam::read_file(bf));
  fs::remove(bf);
  // Threshold: a bracket after the two ends and after a few bisections.
  const fs::path tf = dir / "seed_threshold.json";
  fs::remove(tf);
  for (const auto& [mu_low, mu_high, lps, runs] : {std::tuple{0.0, kMu, 2, 1}, std::tuple{0.0875, 0.09375, 6, 3}}) {
    unjam::ThresholdProgress t;
    t.so_far.mu_low = mu_low;
    t.so_far.mu_high = mu_high;
    t.so_far.lps = lps;
    t.so_far.iterations = 40;
    t.so_far.seconds = 0.01;
    t.runs = runs;
    unjam::ThresholdCheckpoint(tf, threshold_settings()).save(t);
    out.push_back(unjam::read_file(tf));
  }
  fs::remove_all(dir);
  return out;
}

// The saved checkpoints that an input which is a JSON object without "settings" edits: its keys
// replace theirs. So the fuzzer reaches every value of a checkpoint from inputs of a few bytes.
const std::vector<nlohmann::json>& edited_bases() {
  static const std::vector<nlohmann::json> bases = [] {
    const std::vector<std::string> saved = saved_checkpoints();
    return std::vector<nlohmann::json>{nlohmann::json::parse(saved[1]), nlohmann::json::parse(saved[3])};
  }();
  return bases;
}

std::vector<std::string> seeds() {
  std::vector<std::string> out = saved_checkpoints();
  for (const char* edit : {R"({"lps": 7, "runs": 2})", R"({"mu_low": 0.05, "mu_high": 0.0625, "lp_seconds": 1.5})",
                           R"({"iterations": 5, "min_lps_skipped": 0, "unscaled_solves": 2})",
                           R"({"runs": {"runs": 1, "wall_seconds": 1.0, "busy_seconds": 0.5, "untimed": 0}})",
                           R"({"fn_min": [0.5, null], "simplex_iterations": 3})"})
    out.emplace_back(edit);
  return out;
}

// What `read` reads back from a file its own run saved; refusing it breaks the contract.
template <typename Read>
auto reloaded(Read read) {
  try {
    return read();
  } catch (const unjam::Error& e) {
    accepted_invalid(std::string("what was accepted and saved again is refused: ") + e.what());
  }
}

bool same_values(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() != b.size()) return false;
  for (Eigen::Index k = 0; k < a.size(); ++k)
    if (!(std::isnan(a[k]) ? std::isnan(b[k]) : a[k] == b[k])) return false;
  return true;
}

void check_bounds(const fs::path& file) {
  const fs::path again = work_dir() / "bounds_again.json";
  unjam::ForceBounds r;
  unjam::CampaignTime earlier;
  {
    const unjam::BoundsCheckpoint c(file, bounds_settings());
    if (!c.resumed()) accepted_invalid("a bounds checkpoint read as none");
    r = *c.resumed();
    earlier = c.earlier();
  }
  if (r.fn_min.size() != kContacts || r.fn_max.size() != kContacts) accepted_invalid("bounds of another size");
  for (int k = 0; k < kContacts; ++k) {
    if (!std::isnan(r.fn_min[k]) && !(std::isfinite(r.fn_min[k]) && r.fn_min[k] >= 0.0))
      accepted_invalid("a minimum that is neither unknown nor finite and >= 0");
    if (!std::isnan(r.fn_max[k]) && !std::isfinite(r.fn_max[k])) accepted_invalid("an infinite maximum");
  }
  if (r.complete) accepted_invalid("a checkpoint read as complete");
  if (r.min_lps_skipped < 0 || r.min_lps_skipped > kContacts || r.iterations < 0 || r.loosened_solves < 0 ||
      r.simplex_finishes < 0 || r.unscaled_solves < 0)
    accepted_invalid("bounds' counts out of range");
  const long long known = unjam::known_values(r);
  if (!(earlier.runs >= 0 && std::isfinite(earlier.wall_seconds) && earlier.wall_seconds >= 0.0 &&
        std::isfinite(earlier.busy_seconds) && earlier.busy_seconds >= 0.0 && earlier.untimed >= 0 &&
        earlier.untimed <= known))
    accepted_invalid("a record of the runs' time out of range");
  // Saved again by its own run, it reads back unchanged.
  fs::remove(again);
  unjam::BoundsCheckpoint(again, bounds_settings()).save(r, earlier);
  const auto [s, s_earlier] = reloaded([&] {
    const unjam::BoundsCheckpoint c(again, bounds_settings());
    return std::pair{*c.resumed(), c.earlier()};
  });
  if (!same_values(s.fn_min, r.fn_min) || !same_values(s.fn_max, r.fn_max) ||
      s.min_lps_skipped != r.min_lps_skipped || s.iterations != r.iterations ||
      s.loosened_solves != r.loosened_solves || s.simplex_finishes != r.simplex_finishes ||
      s.unscaled_solves != r.unscaled_solves || s_earlier.runs != earlier.runs ||
      s_earlier.wall_seconds != earlier.wall_seconds || s_earlier.busy_seconds != earlier.busy_seconds ||
      s_earlier.untimed != earlier.untimed)
    accepted_invalid("bounds that do not reload as saved");
  fs::remove(again);
}

void check_threshold(const fs::path& file) {
  const fs::path again = work_dir() / "threshold_again.json";
  unjam::ThresholdProgress p;
  {
    const unjam::ThresholdCheckpoint c(file, threshold_settings());
    if (!c.resumed()) accepted_invalid("a threshold checkpoint read as none");
    p = *c.resumed();
  }
  const unjam::FrictionThreshold& t = p.so_far;
  if (t.mu != kMu) accepted_invalid("a bracket of another mu than the run's");
  if (!(t.mu_low >= 0.0 && t.mu_high > t.mu_low && t.mu_high <= kMu)) accepted_invalid("a bracket out of range");
  if (t.lps < 0 || t.iterations < 0 || !(std::isfinite(t.seconds) && t.seconds >= 0.0) || p.runs < 1)
    accepted_invalid("threshold counts out of range");
  fs::remove(again);
  unjam::ThresholdCheckpoint(again, threshold_settings()).save(p);
  const unjam::ThresholdProgress q =
      reloaded([&] { return *unjam::ThresholdCheckpoint(again, threshold_settings()).resumed(); });
  if (q.so_far.mu_low != t.mu_low || q.so_far.mu_high != t.mu_high || q.so_far.lps != t.lps ||
      q.so_far.iterations != t.iterations || q.so_far.seconds != t.seconds || q.runs != p.runs)
    accepted_invalid("a bracket that does not reload as saved");
  fs::remove(again);
}

// Both readers on `text` as a checkpoint file's contents.
void read_both(const std::string& text) {
  const fs::path file = work_dir() / "checkpoint.json";
  std::ofstream(file, std::ios::binary | std::ios::trunc) << text;
  try {
    check_bounds(file);
  } catch (const unjam::Error&) {
  }
  try {
    check_threshold(file);
  } catch (const unjam::Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  unjam::fuzz::write_seeds_if_asked(*argc, *argv, seeds);
  (void)edited_bases();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  fs::create_directories(work_dir());
  read_both(text);
  const auto edit = nlohmann::json::parse(text, nullptr, false);
  if (edit.is_object() && !edit.contains("settings")) {
    for (nlohmann::json base : edited_bases()) {
      for (const auto& [key, value] : edit.items()) base[key] = value;
      read_both(base.dump());
    }
  }
  fs::remove_all(work_dir());
  return 0;
}
