// unjam.CdSettings: the cd method's settings (CdPathSettings) as one typed object, the fields
// that `unjam probe --cd-*` sets, under the options' names without the prefix (--cd-max-pieces:
// max_pieces). Every assignment is range-checked as the tool checks its options (validate of
// CdPathSettings); what depends on the method or the start (e.g. compliant_start with the
// static start) is checked where unjam.probe takes them (docs/probe.md, "At a glance").
#include <sstream>
#include <string>

#include "python/bindings.hpp"
#include "unjam/probe/cd_path.hpp"
#include "unjam/probe/probe_campaign.hpp"

namespace unjam::python {
namespace {

using Class = py::class_<CdPathSettings>;

// A read-write field whose every assignment is checked: the settings change only if the new
// value passes validate(CdPathSettings).
template <class T>
void checked_field(Class& c, const char* name, T CdPathSettings::*member, const char* doc) {
  c.def_property(
      name, [member](const CdPathSettings& s) { return s.*member; },
      [member](CdPathSettings& s, T value) {
        CdPathSettings t = s;
        t.*member = value;
        validate(t);
        s = t;
      },
      doc);
}

// The fields CdSettings shows, by name in the constructor's order: its repr, its pickled
// state and what == compares.
py::dict fields(const CdPathSettings& s) {
  py::dict d;
  d["start"] = std::string(cd_start_name(s.start));
  d["compliant_start"] = s.compliant_start;
  d["softer_starts"] = s.softer_starts;
  d["max_pieces"] = s.max_probe_pieces;
  d["accept_residual"] = s.accept_residual;
  d["interior_states_pieces"] = s.interior_states_pieces;
  d["interior_states_stall"] = s.interior_states_stall;
  d["interior_states_retries"] = s.interior_states_retries;
  d["interior_iterations"] = s.interior_max_iterations;
  d["interior_neighbourhood"] = s.interior_neighbourhood;
  d["settle_compliance"] = s.settle_compliance;
  d["lost_factor"] = s.lost_factor;
  d["restart_floor"] = s.restart_floor;
  d["interior_share"] = s.interior_share;
  d["inertial_factor"] = s.inertial_factor;
  d["inertial_stages"] = s.inertial_stages;
  d["inertial_halvings"] = s.inertial_halvings;
  d["inertial_retries"] = s.inertial_retries;
  d["inertial_jumps"] = s.inertial_jumps;
  return d;
}

// CdSettings(start='static', compliant_start=0.1, ...): each value as Python writes it.
std::string repr(const CdPathSettings& s) {
  std::ostringstream o;
  o << "CdSettings(";
  const char* sep = "";
  for (const auto& [name, value] : fields(s)) {
    o << sep << name.cast<std::string>() << "=" << py::repr(value).cast<std::string>();
    sep = ", ";
  }
  o << ")";
  return o.str();
}

}  // namespace

bool same_cd_fields(const CdPathSettings& a, const CdPathSettings& b) { return fields(a).equal(fields(b)); }

CdPathSettings cd_settings(const std::string& start, double compliant_start, int softer_starts, long long max_pieces,
                           double accept_residual, double interior_states_pieces, int interior_states_stall,
                           int interior_states_retries, int interior_iterations, double interior_neighbourhood) {
  CdPathSettings s;
  s.start = cd_start_from_name(start);
  s.compliant_start = compliant_start;
  s.softer_starts = softer_starts;
  s.max_probe_pieces = max_pieces;
  s.accept_residual = accept_residual;
  s.interior_states_pieces = interior_states_pieces;
  s.interior_states_stall = interior_states_stall;
  s.interior_states_retries = interior_states_retries;
  s.interior_max_iterations = interior_iterations;
  s.interior_neighbourhood = interior_neighbourhood;
  return s;
}

void bind_cd_settings(py::module_& m) {
  const CdPathSettings d;
  Class c(m, "CdSettings",
          "the cd method's settings, as `unjam probe --cd-*` sets them (each field is the option "
          "without its --cd- prefix; the defaults are the tool's); pass one as unjam.probe(..., "
          "method='cd', cd=settings). Every assignment is range-checked; docs/probe.md");
  c.def(py::init([](const std::string& start, double compliant_start, int softer_starts, long long max_pieces,
                    double accept_residual, double interior_states_pieces, int interior_states_stall,
                    int interior_states_retries, int interior_iterations, double interior_neighbourhood,
                    double settle_compliance, double lost_factor, double restart_floor, double interior_share,
                    double inertial_factor, int inertial_stages, int inertial_halvings, int inertial_retries,
                    int inertial_jumps) {
          CdPathSettings s = cd_settings(start, compliant_start, softer_starts, max_pieces, accept_residual,
                                         interior_states_pieces, interior_states_stall, interior_states_retries,
                                         interior_iterations, interior_neighbourhood);
          s.settle_compliance = settle_compliance;
          s.lost_factor = lost_factor;
          s.restart_floor = restart_floor;
          s.interior_share = interior_share;
          s.inertial_factor = inertial_factor;
          s.inertial_stages = inertial_stages;
          s.inertial_halvings = inertial_halvings;
          s.inertial_retries = inertial_retries;
          s.inertial_jumps = inertial_jumps;
          validate(s);
          return s;
        }),
        py::kw_only(), py::arg("start") = cd_start_name(d.start), py::arg("compliant_start") = d.compliant_start,
        py::arg("softer_starts") = d.softer_starts, py::arg("max_pieces") = d.max_probe_pieces,
        py::arg("accept_residual") = d.accept_residual,
        py::arg("interior_states_pieces") = d.interior_states_pieces,
        py::arg("interior_states_stall") = d.interior_states_stall,
        py::arg("interior_states_retries") = d.interior_states_retries,
        py::arg("interior_iterations") = d.interior_max_iterations,
        py::arg("interior_neighbourhood") = d.interior_neighbourhood,
        py::arg("settle_compliance") = d.settle_compliance, py::arg("lost_factor") = d.lost_factor,
        py::arg("restart_floor") = d.restart_floor, py::arg("interior_share") = d.interior_share,
        py::arg("inertial_factor") = d.inertial_factor, py::arg("inertial_stages") = d.inertial_stages,
        py::arg("inertial_halvings") = d.inertial_halvings, py::arg("inertial_retries") = d.inertial_retries,
        py::arg("inertial_jumps") = d.inertial_jumps);
  c.def_property(
      "start", [](const CdPathSettings& s) { return std::string(cd_start_name(s.start)); },
      [](CdPathSettings& s, const std::string& name) { s.start = cd_start_from_name(name); },
      "where the path starts: 'static', 'compliant', 'lp', 'interior', 'inertial' or 'interior-inertial' "
      "(--cd-start; docs/probe.md, \"Where the path starts\")");
  checked_field(c, "compliant_start", &CdPathSettings::compliant_start,
                "the compliance of the compliant continuation's first path, > 0 (--cd-compliant-start; "
                "docs/probe.md, \"Where the continuation starts\")");
  checked_field(c, "softer_starts", &CdPathSettings::softer_starts,
                "the continuation's softer starts (compliant and interior starts), >= 0 (--cd-softer-starts)");
  checked_field(c, "max_pieces", &CdPathSettings::max_probe_pieces,
                "a probe's budget of pieces over all its paths, >= 0 (0: none; --cd-max-pieces; "
                "docs/probe.md, \"A budget of pieces per probe\")");
  checked_field(c, "accept_residual", &CdPathSettings::accept_residual,
                "the residual (g) at which a probe stops at a near-exact solution, 1e-6 (the default: only "
                "an exact one) to 1e-3 (--cd-accept-residual; docs/probe.md, \"Accepting a near-exact "
                "solution\")");
  checked_field(c, "interior_states_pieces", &CdPathSettings::interior_states_pieces,
                "interior start: the cut of the path from the iterate's own states, pieces per contact, "
                ">= 0 (--cd-interior-states-pieces)");
  checked_field(c, "interior_states_stall", &CdPathSettings::interior_states_stall,
                "interior start: pieces without progress that cut that path, >= 0 "
                "(--cd-interior-states-stall)");
  checked_field(c, "interior_states_retries", &CdPathSettings::interior_states_retries,
                "interior start: that path's retries at 10x its compliance, >= 0 "
                "(--cd-interior-states-retries)");
  checked_field(c, "interior_iterations", &CdPathSettings::interior_max_iterations,
                "interior start: the interior-point method's cap of iterations, >= 1 "
                "(--cd-interior-iterations)");
  checked_field(c, "interior_neighbourhood", &CdPathSettings::interior_neighbourhood,
                "interior start: the wide neighbourhood of a second interior-point run, in [0, 1) (0: none; "
                "--cd-interior-neighbourhood)");
  checked_field(c, "settle_compliance", &CdPathSettings::settle_compliance,
                "the compliance at or below which a path ends at its first exact solution, >= 0 (0: never; "
                "--cd-settle-compliance; docs/probe.md, \"Settling at an exact solution\")");
  checked_field(c, "lost_factor", &CdPathSettings::lost_factor,
                "drop a path whose forces at the full opening have a residual above this factor times its "
                "compliance (at least 1e-3) in g, >= 0 (0: off; --cd-lost-factor; docs/probe.md, \"Paths that "
                "lose their digits\")");
  checked_field(c, "restart_floor", &CdPathSettings::restart_floor,
                "the compliance below which the compliant continuation is not restarted (its next softer start "
                "follows instead), >= 0 (0: every restart; --cd-restart-floor; docs/probe.md, \"Restarts below a "
                "floor\")");
  checked_field(c, "interior_share", &CdPathSettings::interior_share,
                "interior-inertial start: the fraction of max_pieces the interior start may take before the "
                "continuation in dt takes the rest, in (0, 1) (--cd-interior-share; docs/probe.md, \"The "
                "interior start first, the continuation in dt where it fails\")");
  checked_field(c, "inertial_factor", &CdPathSettings::inertial_factor,
                "inertial and interior-inertial starts: the continuation in dt starts from the step at dt / this, "
                "> 1 (--cd-inertial-factor; docs/probe.md, \"The quasi-static step as the limit of vanishing "
                "inertia\")");
  checked_field(c, "inertial_stages", &CdPathSettings::inertial_stages,
                "inertial and interior-inertial starts: log dt advances by at most log(inertial_factor) / this per "
                "stage, >= 1 (--cd-inertial-stages)");
  checked_field(c, "inertial_halvings", &CdPathSettings::inertial_halvings,
                "inertial and interior-inertial starts: halvings in a row of a stage's step in dt before the branch "
                "counts as folded, >= 0 (--cd-inertial-halvings)");
  checked_field(c, "inertial_retries", &CdPathSettings::inertial_retries,
                "inertial and interior-inertial starts: new first stages at sqrt(10) times less dt, >= 0 "
                "(--cd-inertial-retries)");
  checked_field(c, "inertial_jumps", &CdPathSettings::inertial_jumps,
                "inertial and interior-inertial starts: jumps to another branch past a fold in dt per probe, >= 0 "
                "(--cd-inertial-jumps)");
  c.def("__repr__", &repr);
  c.def("__eq__", [](const CdPathSettings& a, const CdPathSettings& b) { return same_cd_fields(a, b); }, py::is_operator());
  c.def("__copy__", [](const CdPathSettings& s) { return s; });
  c.def("__deepcopy__", [](const CdPathSettings& s, py::dict) { return s; }, py::arg("memo"));
  // pickle (multiprocessing, saving a configuration): the fields of repr as a dict by name, read
  // back by the checked constructor.
  c.def(py::pickle(
      [](const CdPathSettings& s) { return fields(s); },
      [](const py::dict& d) { return py::type::of<CdPathSettings>()(**d).cast<CdPathSettings>(); }));
}

}  // namespace unjam::python
