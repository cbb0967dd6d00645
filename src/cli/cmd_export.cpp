// `unjam export DIR --format vtk|xyz`: the packing for ParaView (VTK XML PolyData .vtp) or
// OVITO (extended XYZ), optionally with one probe's displacement field, computed here
// (--probe K) or read from `unjam probe --contact K`'s probe-K.csv (--field FILE).
// Formats: src/unjam/packing/export.hpp and docs/packing-format.md.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "cli/commands.hpp"
#include "cli/run_info.hpp"
#include "unjam/core/atomic_file.hpp"
#include "unjam/core/error.hpp"
#include "unjam/packing/export.hpp"
#include "unjam/packing/packing_io.hpp"
#include "unjam/probe/probe_campaign.hpp"

namespace unjam::cli {
namespace {

struct ExportOptions {
  std::string dir, format, out, field, method = "lp";
  int probe = -1;
};

std::optional<GrainDisplacement> displacement(const ExportOptions& o, const Packing& p) {
  if (o.probe >= 0 && !o.field.empty()) throw Error("give --probe K or --field FILE, not both");
  if (!o.field.empty()) return read_displacement_csv(o.field, p.size());
  if (o.probe < 0) return std::nullopt;
  if (o.probe >= static_cast<int>(p.contacts.size()))
    throw Error("--probe " + std::to_string(o.probe) + ": the packing has " +
                std::to_string(p.contacts.size()) + " contacts");
  CampaignSettings s = campaign_settings_for(p);
  s.method = method_from_name(o.method);
  return grain_displacement(probe_contact(p, s, o.probe));
}

void run(const ExportOptions& o) {
  const Packing p = read_packing(o.dir);
  const std::optional<GrainDisplacement> field = displacement(o, p);
  const bool vtk = o.format == "vtk";
  std::filesystem::path out = o.out;
  if (out.empty()) {
    const std::string stem = field && o.probe >= 0 ? "probe-" + std::to_string(o.probe) : "packing";
    out = std::filesystem::path(o.dir) / (stem + (vtk ? ".vtp" : ".xyz"));
  }
  const GrainDisplacement* f = field ? &*field : nullptr;
  const ExportRecord record{o.dir, command_line()};
  write_file_atomic(out, vtk ? vtk_polydata(p, f, record) : extended_xyz(p, f, record));
  std::printf("%zu grains, %zu contacts%s -> %s\n", p.size(), p.contacts.size(),
              f ? ", with a displacement field" : "", out.c_str());
}

}  // namespace

void add_export_command(CLI::App& app) {
  auto o = std::make_shared<ExportOptions>();
  CLI::App* cmd = app.add_subcommand(
      "export", "write a packing for ParaView (VTK .vtp) or OVITO (extended XYZ)");
  cmd->add_option("dir", o->dir, "packing directory")->required();
  cmd->add_option("--format", o->format, "vtk (ParaView: grains as points, contacts as lines) or "
                                         "xyz (OVITO: extended XYZ, grains only)")
      ->required()
      ->check(CLI::IsMember({"vtk", "xyz"}));
  cmd->add_option("--out", o->out, "output file (default DIR/packing.vtp|.xyz, DIR/probe-K.vtp|.xyz with --probe)");
  cmd->add_option("--probe", o->probe, "probe this contact and add its displacement field");
  cmd->add_option("--method", o->method, "probe method of --probe: lp, nlgs, lemke or cd")->capture_default_str();
  cmd->add_option("--field", o->field, "add the displacement field of a probe-K.csv (unjam probe --contact K)");
  cmd->callback([o] { run(*o); });
}

}  // namespace unjam::cli
