#include "unjam/packing/packing_io.hpp"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/version.hpp"
#include "unjam/packing/csv_table.hpp"

namespace unjam {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kMeta = "meta.json";
constexpr const char* kParticles = "particles.csv";
constexpr const char* kContacts = "contacts.csv";

// |n| must be 1 within this tolerance.
constexpr double kNormalTolerance = 1e-6;

// FNV-1a, 64 bit, of the bytes of a file, as 16 hex digits.
std::string fnv1a64_hex(std::string_view bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

json checksum_of(std::string_view bytes) {
  return {{"fnv1a64", fnv1a64_hex(bytes)}, {"bytes", bytes.size()}};
}

// ---- meta.json ---------------------------------------------------------------------------

// The value of a required key, checked to be a finite number.
double meta_number(const json& meta, const std::string& where, const char* key) {
  const auto it = meta.find(key);
  if (it == meta.end()) throw Error(where + ": missing '" + key + "'");
  if (!it->is_number()) throw Error(where + ": '" + key + "' must be a number, found " + it->dump());
  const double v = it->get<double>();
  if (!std::isfinite(v)) throw Error(where + ": '" + key + "' is not finite");
  return v;
}

double meta_number_or(const json& meta, const std::string& where, const char* key, double fallback) {
  return meta.contains(key) ? meta_number(meta, where, key) : fallback;
}

// The value of an optional string key, empty if absent.
std::string meta_string_or(const json& meta, const std::string& where, const char* key) {
  const auto it = meta.find(key);
  if (it == meta.end()) return {};
  if (!it->is_string()) throw Error(where + ": '" + key + "' must be a string, found " + it->dump());
  return it->get<std::string>();
}

std::int64_t meta_integer(const json& v, const std::string& where, const std::string& key) {
  if (!v.is_number_integer() && !(v.is_number_float() && v.get<double>() == std::trunc(v.get<double>())))
    throw Error(where + ": '" + key + "' must be an integer, found " + v.dump());
  return v.get<std::int64_t>();
}

struct MetaFile {
  json meta;
  std::optional<std::int64_t> N;  // grain count, if the meta gives it
};

MetaFile read_meta(const fs::path& path, Packing& p) {
  const std::string where = path.string();
  const std::string text = read_file(path);
  MetaFile m;
  try {
    m.meta = json::parse(text);
  } catch (const json::parse_error& e) {
    throw Error(where + ": not valid JSON (" + e.what() + ")");
  }
  const json& meta = m.meta;
  if (!meta.is_object()) throw Error(where + ": expected a JSON object");

  if (const auto it = meta.find("format_version"); it != meta.end()) {
    const std::int64_t v = meta_integer(*it, where, "format_version");
    if (v > kPackingFormatVersion)
      throw Error(where + ": format_version " + std::to_string(v) + " is newer than this unjam reads (" +
                  std::to_string(kPackingFormatVersion) + ")");
  }
  // The cell: Lx and Ly, or L for a square cell.
  if (meta.contains("Lx") || meta.contains("Ly")) {
    p.cell.Lx = meta_number(meta, where, "Lx");
    p.cell.Ly = meta_number(meta, where, "Ly");
  } else if (meta.contains("L")) {
    p.cell.Lx = p.cell.Ly = meta_number(meta, where, "L");
  } else {
    throw Error(where + ": missing the cell size ('L', or 'Lx' and 'Ly')");
  }
  if (!(p.cell.Lx > 0.0 && p.cell.Ly > 0.0)) throw Error(where + ": the cell size must be positive");
  p.meta.P_ext = meta_number(meta, where, "P_ext");
  if (!(p.meta.P_ext > 0.0)) throw Error(where + ": 'P_ext' must be positive");
  p.meta.mu = meta_number(meta, where, "mu");
  if (p.meta.mu < 0.0) throw Error(where + ": 'mu' must not be negative");

  if (const auto it = meta.find("N"); it != meta.end()) m.N = meta_integer(*it, where, "N");
  if (const auto it = meta.find("seed"); it != meta.end()) {
    if (!it->is_number_unsigned()) throw Error(where + ": 'seed' must be a non-negative integer");
    p.meta.seed = it->get<std::uint64_t>();
  }
  if (const auto it = meta.find("settings"); it != meta.end()) p.meta.settings = *it;
  p.meta.command = meta_string_or(meta, where, "command");
  p.meta.program_version = meta_string_or(meta, where, "program_version");

  if (const auto it = meta.find("state"); it != meta.end()) {
    if (!it->is_object()) throw Error(where + ": 'state' must be an object");
    const std::string w = where + " state";
    p.state.time = meta_number_or(*it, w, "time", 0.0);
    if (const auto s = it->find("step"); s != it->end()) p.state.step = meta_integer(*s, w, "step");
    p.state.lambda = meta_number_or(*it, w, "lambda", 0.0);
    if (const auto s = it->find("static"); s != it->end()) {
      if (!s->is_boolean()) throw Error(w + ": 'static' must be true or false");
      p.state.is_static = s->get<bool>();
    }
  }
  return m;
}

// Compares a table's bytes with the checksum meta.json recorded for it, if any.
void verify_checksum(const json& meta, const fs::path& dir, const char* file, std::string_view bytes) {
  const auto all = meta.find("checksums");
  if (all == meta.end()) return;
  const auto it = all->find(file);
  if (it == all->end()) return;
  if (*it != checksum_of(bytes))
    throw Error((dir / file).string() +
                " does not match meta.json: the packing was modified or its write was interrupted");
}

// ---- particles.csv -----------------------------------------------------------------------

void read_particles(const CsvTable& t, Packing& p) {
  const std::size_t n = t.rows();
  if (n == 0) throw Error(t.name() + ": no particles");
  const std::size_t cx = t.column("x"), cy = t.column("y"), cr = t.column("radius");
  const auto cid = t.find_column("id");
  const auto cvx = t.find_column("vx"), cvy = t.find_column("vy"), cw = t.find_column("omega");

  Particles& P = p.particles;
  P.resize(n);
  std::vector<bool> seen(n, false);
  for (std::size_t row = 0; row < n; ++row) {
    // Rows may come in any order when ids are given; each goes to its id.
    std::size_t i = row;
    if (cid) {
      const std::int64_t id = t.integer(row, *cid);
      if (id < 0 || id >= static_cast<std::int64_t>(n))
        t.fail(row, "id " + std::to_string(id) + " out of range (ids must be 0.." + std::to_string(n - 1) + ")");
      i = static_cast<std::size_t>(id);
      if (seen[i]) t.fail(row, "duplicate id " + std::to_string(id));
      seen[i] = true;
    }
    const Vec2 r = p.cell.wrap({t.number(row, cx), t.number(row, cy)});
    P.x[i] = r.x();
    P.y[i] = r.y();
    P.radius[i] = t.number(row, cr);
    if (!(P.radius[i] > 0.0)) t.fail(row, "radius must be positive");
    if (cvx) P.vx[i] = t.number(row, *cvx);
    if (cvy) P.vy[i] = t.number(row, *cvy);
    if (cw) P.omega[i] = t.number(row, *cw);
  }
}

// ---- contacts.csv ------------------------------------------------------------------------

void read_contacts(const CsvTable& t, Packing& p) {
  const std::size_t ca = t.column("a"), cb = t.column("b");
  const std::size_t cnx = t.column("nx"), cny = t.column("ny");
  const std::size_t clx = t.column("lx"), cly = t.column("ly");
  const std::size_t cfn = t.column("fn"), cft = t.column("ft");
  const auto cgap = t.find_column("gap");

  const auto N = static_cast<std::int64_t>(p.size());
  const Particles& P = p.particles;
  p.contacts.resize(t.rows());
  for (std::size_t row = 0; row < t.rows(); ++row) {
    Contact& c = p.contacts[row];
    const std::int64_t a = t.integer(row, ca), b = t.integer(row, cb);
    for (const std::int64_t k : {a, b})
      if (k < 0 || k >= N)
        t.fail(row, "grain index " + std::to_string(k) + " out of range (0.." + std::to_string(N - 1) + ")");
    if (a == b) t.fail(row, "contact of grain " + std::to_string(a) + " with itself");
    c.a = static_cast<int>(a);
    c.b = static_cast<int>(b);
    c.n = {t.number(row, cnx), t.number(row, cny)};
    if (std::abs(c.n.norm() - 1.0) > kNormalTolerance)
      t.fail(row, "the normal (nx, ny) is not a unit vector (|n| = " + std::to_string(c.n.norm()) + ")");
    c.l = {t.number(row, clx), t.number(row, cly)};
    c.fn = t.number(row, cfn);
    c.ft = t.number(row, cft);
    if (cgap) {
      c.gap = t.number(row, *cgap);
    } else {  // gap = |l| - R_a - R_b, l from the positions (minimum image)
      const Vec2 l = p.cell.min_image(P.position(c.b) - P.position(c.a));
      c.gap = l.norm() - P.radius[c.a] - P.radius[c.b];
    }
  }
}

}  // namespace

Packing read_packing(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw Error("packing directory " + dir.string() + " does not exist");
  for (const char* file : {kMeta, kParticles, kContacts})
    if (!fs::exists(dir / file, ec)) throw Error("packing " + dir.string() + ": missing " + file);

  Packing p;
  const MetaFile meta = read_meta(dir / kMeta, p);

  std::string particles_text = read_file(dir / kParticles);
  verify_checksum(meta.meta, dir, kParticles, particles_text);
  const CsvTable particles = CsvTable::parse(std::move(particles_text), (dir / kParticles).string());
  if (meta.N && *meta.N != static_cast<std::int64_t>(particles.rows()))
    throw Error((dir / kMeta).string() + ": N = " + std::to_string(*meta.N) + " but " + kParticles + " has " +
                std::to_string(particles.rows()) + " rows");
  read_particles(particles, p);

  std::string contacts_text = read_file(dir / kContacts);
  verify_checksum(meta.meta, dir, kContacts, contacts_text);
  read_contacts(CsvTable::parse(std::move(contacts_text), (dir / kContacts).string()), p);
  return p;
}

void write_packing(const fs::path& dir, const Packing& p) {
  const Particles& P = p.particles;
  CsvWriter particles({"id", "x", "y", "radius", "vx", "vy", "omega"});
  for (std::size_t i = 0; i < p.size(); ++i) {
    particles.cell(static_cast<std::int64_t>(i)).cell(P.x[i]).cell(P.y[i]).cell(P.radius[i]);
    particles.cell(P.vx[i]).cell(P.vy[i]).cell(P.omega[i]).end_row();
  }
  CsvWriter contacts({"a", "b", "nx", "ny", "lx", "ly", "gap", "fn", "ft"});
  for (const Contact& c : p.contacts) {
    contacts.cell(c.a).cell(c.b).cell(c.n.x()).cell(c.n.y()).cell(c.l.x()).cell(c.l.y());
    contacts.cell(c.gap).cell(c.fn).cell(c.ft).end_row();
  }

  nlohmann::ordered_json meta;  // keys in the order of docs/packing-format.md
  meta["format_version"] = kPackingFormatVersion;
  meta["program_version"] = kVersion;
  meta["N"] = p.size();
  meta["Lx"] = p.cell.Lx;
  meta["Ly"] = p.cell.Ly;
  if (p.cell.Lx == p.cell.Ly) meta["L"] = p.cell.Lx;
  meta["P_ext"] = p.meta.P_ext;
  meta["mu"] = p.meta.mu;
  meta["seed"] = p.meta.seed;
  meta["F0"] = p.force_unit();
  meta["settings"] = nlohmann::ordered_json(p.meta.settings);
  meta["command"] = p.meta.command;
  meta["state"] = {{"time", p.state.time},
                   {"step", p.state.step},
                   {"lambda", p.state.lambda},
                   {"static", p.state.is_static}};
  meta["checksums"] = {{kParticles, checksum_of(particles.str())}, {kContacts, checksum_of(contacts.str())}};

  // Tables first, meta.json last: a write interrupted in between leaves checksums that no
  // longer match, which read_packing reports.
  write_file_atomic(dir / kParticles, particles.str());
  write_file_atomic(dir / kContacts, contacts.str());
  write_file_atomic(dir / kMeta, meta.dump(2) + "\n");
}

}  // namespace unjam
