// `unjam merge DIR`: joins the shards of a scheduler job array (`unjam probe ... --shard i/K`,
// `unjam bounds ... --shard i/K`, one job each) into the files one run would have written,
// byte for byte (the rows are sorted by contact, the averages are fixed-point sums); with
// --status it prints how far a probe campaign or the force bounds, whole or as a job array, have
// got (campaign_status.cpp).
#include <cstdio>
#include <memory>
#include <string>

#include "cli/commands.hpp"
#include "cli/shards.hpp"
#include "unjam/core/error.hpp"

namespace unjam::cli {

void add_merge_command(CLI::App& app) {
  struct Options {
    std::string dir, out;
    bool status = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "merge", "join the outputs of `probe --shard i/K` and `bounds --shard i/K` jobs into those of one run");
  cmd->add_option("dir", o->dir, "packing directory")->required();
  cmd->add_option("--out", o->out, "directory of the shard files and the outputs (default: the packing directory)");
  cmd->add_flag("--status", o->status,
                "print how far the probe campaign and the force bounds in the output directory have got (each "
                "shard of a job array, or the whole run's checkpoint; the busy time left at its pace) and change "
                "nothing");
  cmd->callback([o] {
    if (o->status) {
      const bool probes = print_probe_status(o->dir, o->out);
      const bool bounds = print_bounds_status(o->dir, o->out);
      if (!probes && !bounds)
        throw Error("no probe campaign or force bounds in " + (o->out.empty() ? o->dir : o->out) +
                    " (none of probe_checkpoint.json, probe_shard-i-of-K.json, probe_checkpoint-shard-i-of-K.json, "
                    "probe_summary.json, bounds_checkpoint.json, bounds_shard-i-of-K.json, "
                    "bounds_checkpoint-shard-i-of-K.json, bounds.json)");
      return;
    }
    const auto lock = lock_output(o->out.empty() ? o->dir : o->out, 0, 1);  // the merged outputs' writer
    const bool probes = merge_probe_shards(o->dir, o->out);
    const bool bounds = merge_bounds_shards(o->dir, o->out);
    if (!probes && !bounds)
      throw Error("no shard outputs (probe_shard-i-of-K.json, bounds_shard-i-of-K.json) in " +
                  (o->out.empty() ? o->dir : o->out));
  });
}

}  // namespace unjam::cli
