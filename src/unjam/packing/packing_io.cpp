#include "unjam/packing/packing_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/json_integer.hpp"
#include "unjam/core/version.hpp"
#include "unjam/packing/csv_table.hpp"
#include "unjam/packing/geometry_check.hpp"

namespace unjam {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kMeta = "meta.json";
constexpr const char* kParticles = "particles.csv";
constexpr const char* kContacts = "contacts.csv";

// |n| must be 1 within this tolerance.
constexpr double kNormalTolerance = 1e-6;

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

// The contact model's entries of "settings" (PackingMeta::contact): settings[group][key], or
// nullptr where settings, its group or the key is missing.
const json* model_entry(const json& settings, const char* group, const char* key) {
  if (!settings.is_object()) return nullptr;
  const auto g = settings.find(group);
  if (g == settings.end() || !g->is_object()) return nullptr;
  const auto k = g->find(key);
  return k == g->end() ? nullptr : &*k;
}

void read_model_entry(const json& settings, const char* group, const char* key, const std::string& where,
                      double& value) {
  if (const json* v = model_entry(settings, group, key)) {
    if (!v->is_number())
      throw Error(where + ": 'settings' " + group + "." + key + " must be a number, found " + v->dump());
    value = v->get<double>();
  }
}

// Stores value as settings[group][key] unless that already holds it, or (missing) value is the
// default: a packing read and written again keeps its bytes.
void write_model_entry(json& settings, const char* group, const char* key, double value, double default_value) {
  const json* v = model_entry(settings, group, key);
  if (v ? v->is_number() && v->get<double>() == value : value == default_value) return;
  if (!settings.is_object()) settings = json::object();
  json& g = settings[group];
  if (!g.is_object()) g = json::object();
  g[key] = value;
}

// The value of an optional string key, empty if absent.
std::string meta_string_or(const json& meta, const std::string& where, const char* key) {
  const auto it = meta.find(key);
  if (it == meta.end()) return {};
  if (!it->is_string()) throw Error(where + ": '" + key + "' must be a string, found " + it->dump());
  return it->get<std::string>();
}

std::int64_t meta_integer(const json& v, const std::string& where, const std::string& key) {
  return json_integer<std::int64_t>(v, where + ": '" + key + "'");
}

struct MetaFile {
  json meta;
  std::optional<std::int64_t> N;  // grain count, if the meta gives it
};

MetaFile read_meta(const fs::path& path, const std::string& text, Packing& p) {
  const std::string where = path.string();
  MetaFile m;
  try {
    m.meta = json::parse(text);
  } catch (const json::exception& e) {  // a syntax error, or a number out of range
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
    if (meta.contains("L")) {
      const double L = meta_number(meta, where, "L");
      if (L != p.cell.Lx || L != p.cell.Ly)
        throw Error(where + ": 'L' = " + json(L).dump() + " disagrees with 'Lx' = " + json(p.cell.Lx).dump() +
                    ", 'Ly' = " + json(p.cell.Ly).dump() + " (L is written only for a square cell)");
    }
  } else if (meta.contains("L")) {
    p.cell.Lx = p.cell.Ly = meta_number(meta, where, "L");
  } else {
    throw Error(where + ": missing the cell size ('L', or 'Lx' and 'Ly')");
  }
  if (!(p.cell.Lx > 0.0 && p.cell.Ly > 0.0)) throw Error(where + ": the cell size must be positive");
  p.meta.contact.P_ext = meta_number(meta, where, "P_ext");
  if (!(p.meta.contact.P_ext > 0.0)) throw Error(where + ": 'P_ext' must be positive");
  p.meta.contact.mu = meta_number(meta, where, "mu");
  if (p.meta.contact.mu < 0.0) throw Error(where + ": 'mu' must not be negative");

  if (const auto it = meta.find("N"); it != meta.end()) m.N = meta_integer(*it, where, "N");
  if (const auto it = meta.find("seed"); it != meta.end()) {
    if (!it->is_number_unsigned()) throw Error(where + ": 'seed' must be a non-negative integer");
    p.meta.seed = it->get<std::uint64_t>();
  }
  if (const auto it = meta.find("settings"); it != meta.end()) p.meta.settings = *it;
  read_model_entry(p.meta.settings, "dynamics", "M_lambda", where, p.meta.contact.M_lambda);
  read_model_entry(p.meta.settings, "static", "touch_gap", where, p.meta.contact.touch_gap);
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

// The checksum meta.json records for a table, or null if meta.json has no "checksums" at
// all. Present, it must hold both tables in the form write_packing gives it.
const json* recorded_checksum(const json& meta, const std::string& where, const char* file) {
  const auto all = meta.find("checksums");
  if (all == meta.end()) return nullptr;
  const auto it = all->is_object() ? all->find(file) : all->end();
  if (it == all->end() || !it->is_object() || !it->contains("fnv1a64") || !(*it)["fnv1a64"].is_string() ||
      !it->contains("bytes") || !(*it)["bytes"].is_number_unsigned())
    throw Error(where + ": 'checksums' must give {\"fnv1a64\": \"<16 hex digits>\", \"bytes\": <size>} for " + file +
                " (delete the whole 'checksums' entry to read edited tables)");
  return &*it;
}

bool matches_checksum(const json& meta, const std::string& where, const char* file, std::string_view bytes) {
  const json* sum = recorded_checksum(meta, where, file);
  return sum == nullptr || *sum == checksum_of(bytes);
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

// ---- the files of one write ---------------------------------------------------------------

// write_packing writes the three files as *.new, then renames them into place, meta.json
// last. A write stopped before meta.json.new is complete leaves the previous files intact;
// one stopped while renaming leaves meta.json.new with its tables, each renamed or still
// *.new. Either way one complete version, matching its checksums, is on disk.
constexpr const char* kNew = ".new";

fs::path new_name(const fs::path& dir, const char* file) { return dir / (std::string(file) + kNew); }

struct PackingFiles {
  fs::path meta_path, particles_path, contacts_path;
  std::string meta_text, particles_text, contacts_text;
};

// The version a write stopped while renaming left (meta.json.new and the tables that match
// its checksums), if there is one.
std::optional<PackingFiles> pending_write(const fs::path& dir) {
  std::error_code ec;
  PackingFiles f;
  f.meta_path = new_name(dir, kMeta);
  if (!fs::exists(f.meta_path, ec)) return std::nullopt;
  try {
    f.meta_text = read_file(f.meta_path);
    const json meta = json::parse(f.meta_text, nullptr, false);
    if (!meta.is_object() || !meta.contains("checksums")) return std::nullopt;
    const std::pair<const char*, std::pair<fs::path*, std::string*>> tables[] = {
        {kParticles, {&f.particles_path, &f.particles_text}}, {kContacts, {&f.contacts_path, &f.contacts_text}}};
    for (const auto& [file, out] : tables) {
      for (const fs::path& candidate : {new_name(dir, file), dir / file}) {
        if (!fs::exists(candidate, ec)) continue;
        std::string text = read_file(candidate);
        if (matches_checksum(meta, f.meta_path.string(), file, text)) {
          *out.first = candidate;
          *out.second = std::move(text);
          break;
        }
      }
      if (out.first->empty()) return std::nullopt;
    }
  } catch (const Error&) {
    return std::nullopt;
  }
  return f;
}

// Completes a write that stopped while renaming, or removes the *.new files of one that
// stopped before (the previous version is then intact).
void finish_or_discard_pending_write(const fs::path& dir) {
  if (const auto f = pending_write(dir)) {
    for (const fs::path* path : {&f->particles_path, &f->contacts_path, &f->meta_path})
      if (path->extension() == kNew) rename_file(*path, dir / path->stem());
    sync_directory(dir);
    return;
  }
  std::error_code ec;
  for (const char* file : {kMeta, kParticles, kContacts}) fs::remove(new_name(dir, file), ec);
}

std::string particles_csv(const Packing& p) {
  const Particles& P = p.particles;
  CsvWriter particles({"id", "x", "y", "radius", "vx", "vy", "omega"});
  for (std::size_t i = 0; i < p.size(); ++i) {
    particles.cell(static_cast<std::int64_t>(i)).cell(P.x[i]).cell(P.y[i]).cell(P.radius[i]);
    particles.cell(P.vx[i]).cell(P.vy[i]).cell(P.omega[i]).end_row();
  }
  return particles.str();
}

std::string contacts_csv(const Packing& p) {
  CsvWriter contacts({"a", "b", "nx", "ny", "lx", "ly", "gap", "fn", "ft"});
  for (const Contact& c : p.contacts) {
    contacts.cell(c.a).cell(c.b).cell(c.n.x()).cell(c.n.y()).cell(c.l.x()).cell(c.l.y());
    contacts.cell(c.gap).cell(c.fn).cell(c.ft).end_row();
  }
  return contacts.str();
}

// The grains' area over the cell's: above 1 no arrangement of the disks fits the cell; and
// the cell must be wide enough for the minimum image (Packing::min_cell_side).
void check_packing_fraction(const Packing& p, const fs::path& meta_path) {
  const double phi = p.packing_fraction();
  if (!(phi <= 1.0)) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  ": the grains' area is %.4g times the cell's (Lx x Ly = %.6g x %.6g); the cell is too "
                  "small for its grains or a radius is wrong", phi, p.cell.Lx, p.cell.Ly);
    throw Error(meta_path.string() + buf);
  }
  if (std::min(p.cell.Lx, p.cell.Ly) < p.min_cell_side()) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  ": the cell (%.6g x %.6g) is narrower than 2 (R_1 + R_2) = %.6g, R_1 and R_2 the two "
                  "largest radii: a pair would touch through two periodic images",
                  p.cell.Lx, p.cell.Ly, p.min_cell_side());
    throw Error(meta_path.string() + buf);
  }
}

void check_contact_geometry(const Packing& p, const CsvTable& contacts) {
  const GeometryReport g = check_geometry(p);
  if (g.duplicate)
    contacts.fail(g.duplicate->second, "grains " + std::to_string(p.contacts[g.duplicate->second].a) + " and " +
                                           std::to_string(p.contacts[g.duplicate->second].b) +
                                           " are listed twice (also on line " +
                                           std::to_string(contacts.line(g.duplicate->first)) + ")");
  if (!g.ok()) {
    const Contact& c = p.contacts[*g.worst_contact];
    contacts.fail(*g.worst_contact, "contact " + std::to_string(*g.worst_contact) + " (grains " + std::to_string(c.a) +
                                        "-" + std::to_string(c.b) + ") does not fit the positions and the cell: " +
                                        g.worst_what);
  }
}

// The packing of the three files' texts; meta_path names meta.json (or meta.json.new) in messages.
Packing parse_files(const std::string& meta_text, std::string particles_text, std::string contacts_text,
                    const fs::path& dir, const fs::path& meta_path) {
  Packing p;
  const MetaFile meta = read_meta(meta_path, meta_text, p);
  for (const auto& [file, text] : {std::pair{kParticles, &particles_text}, std::pair{kContacts, &contacts_text}})
    if (!matches_checksum(meta.meta, meta_path.string(), file, *text))
      throw Error((dir / file).string() +
                  " does not match meta.json: the packing was modified or its write was interrupted");

  const CsvTable particles = CsvTable::parse(std::move(particles_text), (dir / kParticles).string());
  if (meta.N && *meta.N != static_cast<std::int64_t>(particles.rows()))
    throw Error((dir / kMeta).string() + ": N = " + std::to_string(*meta.N) + " but " + kParticles + " has " +
                std::to_string(particles.rows()) + " rows");
  read_particles(particles, p);
  check_packing_fraction(p, dir / kMeta);

  const CsvTable contacts = CsvTable::parse(std::move(contacts_text), (dir / kContacts).string());
  read_contacts(contacts, p);
  check_contact_geometry(p, contacts);
  return p;
}

}  // namespace

Packing read_packing(const fs::path& dir) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) throw Error("packing directory " + dir.string() + " does not exist");
  if (!fs::is_directory(dir, ec))
    throw Error(dir.string() + " is a file, not a packing directory (a directory with meta.json, " +
                kParticles + ", " + kContacts + ")");
  PackingFiles f;
  if (auto pending = pending_write(dir)) {
    f = std::move(*pending);
  } else {
    for (const char* file : {kMeta, kParticles, kContacts})
      if (!fs::exists(dir / file, ec)) throw Error("packing " + dir.string() + ": missing " + file);
    f.meta_path = dir / kMeta;
    f.particles_path = dir / kParticles;
    f.contacts_path = dir / kContacts;
    f.meta_text = read_file(f.meta_path);
    f.particles_text = read_file(f.particles_path);
    f.contacts_text = read_file(f.contacts_path);
  }

  return parse_files(f.meta_text, std::move(f.particles_text), std::move(f.contacts_text), dir, f.meta_path);
}

Packing parse_packing(const std::string& meta_text, std::string particles_text, std::string contacts_text,
                      const fs::path& dir) {
  return parse_files(meta_text, std::move(particles_text), std::move(contacts_text), dir, dir / kMeta);
}

void write_packing(const fs::path& dir, const Packing& p) {
  const std::string particles = particles_csv(p), contacts = contacts_csv(p);
  nlohmann::ordered_json meta;  // keys in the order of docs/packing-format.md
  meta["format_version"] = kPackingFormatVersion;
  meta["program_version"] = kVersion;
  meta["N"] = p.size();
  meta["Lx"] = p.cell.Lx;
  meta["Ly"] = p.cell.Ly;
  if (p.cell.Lx == p.cell.Ly) meta["L"] = p.cell.Lx;
  meta["P_ext"] = p.meta.contact.P_ext;
  meta["mu"] = p.meta.contact.mu;
  meta["seed"] = p.meta.seed;
  meta["F0"] = p.force_unit();
  nlohmann::json settings = p.meta.settings;
  const ContactModel defaults;
  write_model_entry(settings, "dynamics", "M_lambda", p.meta.contact.M_lambda, defaults.M_lambda);
  write_model_entry(settings, "static", "touch_gap", p.meta.contact.touch_gap, defaults.touch_gap);
  meta["settings"] = nlohmann::ordered_json(settings);
  meta["command"] = p.meta.command;
  meta["state"] = {{"time", p.state.time},
                   {"step", p.state.step},
                   {"lambda", p.state.lambda},
                   {"static", p.state.is_static}};
  meta["checksums"] = {{kParticles, checksum_of(particles)}, {kContacts, checksum_of(contacts)}};

  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error("cannot create directory " + dir.string() + ": " + ec.message());
  finish_or_discard_pending_write(dir);
  remove_stale_temporaries(dir);
  // Every file as *.new first, meta.json.new last; then renamed into place, meta.json last.
  write_file_atomic(new_name(dir, kParticles), particles);
  write_file_atomic(new_name(dir, kContacts), contacts);
  write_file_atomic(new_name(dir, kMeta), meta.dump(2) + "\n");
  for (const char* file : {kParticles, kContacts, kMeta}) rename_file(new_name(dir, file), dir / file);
  sync_directory(dir);
}

std::string packing_fingerprint(const Packing& p) {
  char cell[64];
  std::snprintf(cell, sizeof cell, "%.17g %.17g\n", p.cell.Lx, p.cell.Ly);
  return fnv1a64_hex(cell + particles_csv(p) + contacts_csv(p));
}

}  // namespace unjam
