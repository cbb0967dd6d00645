// libFuzzer target of the packing reader (parse_packing, as read_packing after reading the
// files). An input is meta.json, particles.csv and contacts.csv separated by NUL bytes
// (missing parts are empty). Every input must end in unjam::Error or in a packing that
// passes the geometric check (packing/geometry_check.hpp) and the reader's documented
// bounds, whose recorded settings (meta.json "settings", read by `pack --resume` and
// `probe`) then read back or end in unjam::Error; a crash, a sanitizer report, a timeout or
// another exception fails.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/geometry_check.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/probe/probe_campaign.hpp"
#include "unjam/protocol/settings_json.hpp"

namespace {

using unjam::fuzz::accepted_invalid;

std::vector<std::string> seeds() {
  std::vector<std::string> out;
  for (const char* name : {"lattice16", "p50-mu0.1", "p50-mu1"}) {
    const std::string meta = unjam::fuzz::fixture_file(name, "meta.json");
    const std::string tables = unjam::fuzz::fixture_file(name, "particles.csv") + '\0' +
                               unjam::fuzz::fixture_file(name, "contacts.csv");
    out.push_back(meta + '\0' + tables);
  }
  // p50-mu1 without its checksums, so that edits of its tables reach the table readers.
  std::string meta = unjam::fuzz::fixture_file("p50-mu1", "meta.json");
  meta.erase(meta.find(",\n  \"checksums\""), std::string::npos);
  out.push_back(meta + "}\n" + '\0' + unjam::fuzz::fixture_file("p50-mu1", "particles.csv") + '\0' +
                unjam::fuzz::fixture_file("p50-mu1", "contacts.csv"));
  return out;
}

// What read_packing promises of a packing it returns, checked independently of its code.
void check_accepted(const unjam::Packing& p) {
  const double Lx = p.cell.Lx, Ly = p.cell.Ly;
  if (!(Lx > 0.0 && Ly > 0.0 && std::isfinite(Lx) && std::isfinite(Ly))) accepted_invalid("cell size");
  if (p.size() == 0) accepted_invalid("no grains");
  const auto& P = p.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!(P.x[i] >= 0.0 && P.x[i] < Lx && P.y[i] >= 0.0 && P.y[i] < Ly))
      accepted_invalid("grain " + std::to_string(i) + " outside the cell [0, Lx) x [0, Ly)");
    if (!(P.radius[i] > 0.0 && std::isfinite(P.radius[i]))) accepted_invalid("radius of grain " + std::to_string(i));
    for (const double v : {P.vx[i], P.vy[i], P.omega[i]})
      if (!std::isfinite(v)) accepted_invalid("velocity of grain " + std::to_string(i));
  }
  if (!(p.packing_fraction() <= 1.0)) accepted_invalid("packing fraction above 1");
  for (const unjam::Contact& c : p.contacts) {
    if (c.a < 0 || c.b < 0 || c.a >= static_cast<int>(p.size()) || c.b >= static_cast<int>(p.size()) || c.a == c.b)
      accepted_invalid("contact grains out of range");
    for (const double v : {c.fn, c.ft, c.gap})
      if (!std::isfinite(v)) accepted_invalid("contact value not finite");
  }
  const unjam::GeometryReport g = unjam::check_geometry(p);
  if (!g.ok()) accepted_invalid("geometric check: " + g.worst_what);
  (void)unjam::packing_fingerprint(p);  // formats every number again
  try {
    (void)unjam::campaign_settings_for(p);
  } catch (const unjam::Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  unjam::fuzz::write_seeds_if_asked(*argc, *argv, seeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  std::string part[3];
  std::size_t k = 0;
  for (const char ch : input) {
    if (ch == '\0' && k < 2) ++k;
    else part[k] += ch;
  }
  try {
    check_accepted(unjam::parse_packing(part[0], std::move(part[1]), std::move(part[2]), "fuzz"));
  } catch (const unjam::Error&) {
    // refused with a message: the contract
  }
  return 0;
}
