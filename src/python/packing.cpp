// unjam.Packing: a packing's data as numpy arrays, read and written like the tool does
// (docs/packing-format.md). The per-grain arrays and the contact columns are read-only views
// into the packing (they keep it alive); positions, velocities and cell are copies.
#include <array>
#include <cstddef>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "python/bindings.hpp"
#include "unjam/packing/export.hpp"
#include "unjam/packing/packing_io.hpp"

namespace unjam::python {
namespace {

// A read-only view of `count` values of type T starting at `data`, `stride` bytes apart
// (and `components` consecutive values per row if > 1), owned by `owner`.
template <class T>
py::array view(const void* data, std::size_t count, std::size_t stride, py::handle owner,
               int components = 1) {
  py::array a;
  if (components == 1)
    a = py::array_t<T>({count}, {stride}, static_cast<const T*>(data), owner);
  else
    a = py::array_t<T>({count, std::size_t(components)}, {stride, sizeof(T)},
                       static_cast<const T*>(data), owner);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

py::array grain_view(const std::vector<double>& v, py::handle owner) {
  return view<double>(v.data(), v.size(), sizeof(double), owner);
}

// Two SoA columns as one (N, 2) array (a copy).
py::array_t<double> pairs(const std::vector<double>& x, const std::vector<double>& y) {
  py::array_t<double> a({x.size(), std::size_t(2)});
  auto r = a.mutable_unchecked<2>();
  for (std::size_t i = 0; i < x.size(); ++i) {
    r(i, 0) = x[i];
    r(i, 1) = y[i];
  }
  return a;
}

// The contact list (an array of structs) as column views with the struct's stride.
py::object contact_columns(const Packing& p, py::handle owner) {
  const Contact probe_layout;
  const auto offset = [&](const void* member) {
    return static_cast<const char*>(member) - reinterpret_cast<const char*>(&probe_layout);
  };
  const auto* base = reinterpret_cast<const char*>(p.contacts.data());
  const std::size_t m = p.contacts.size(), s = sizeof(Contact);
  const auto col = [&](const void* member) { return base + offset(member); };
  py::dict d;
  d["a"] = view<int>(col(&probe_layout.a), m, s, owner);
  d["b"] = view<int>(col(&probe_layout.b), m, s, owner);
  d["n"] = view<double>(col(probe_layout.n.data()), m, s, owner, 2);
  d["l"] = view<double>(col(probe_layout.l.data()), m, s, owner, 2);
  d["gap"] = view<double>(col(&probe_layout.gap), m, s, owner);
  d["fn"] = view<double>(col(&probe_layout.fn), m, s, owner);
  d["ft"] = view<double>(col(&probe_layout.ft), m, s, owner);
  return py::module_::import("types").attr("SimpleNamespace")(**d);
}

}  // namespace

void bind_packing(py::module_& m) {
  py::class_<Packing>(m, "Packing",
                      "A packing: grains, periodic cell, contacts and the record of how it was "
                      "made. Lengths in R_max, forces in simulation units (F0 = 2 R_avg P_ext).")
      .def_property_readonly("N", &Packing::size, "number of grains")
      .def_property_readonly("cell", [](const Packing& p) {
        return py::array_t<double>(2, std::array<double, 2>{p.cell.Lx, p.cell.Ly}.data());
      }, "the cell sides [Lx, Ly] (a copy; the cell is [0, Lx) x [0, Ly), periodic)")
      .def_property_readonly("positions", [](const Packing& p) { return pairs(p.particles.x, p.particles.y); },
                             "(N, 2) float64 centres (a copy; views: x, y)")
      .def_property_readonly("velocities", [](const Packing& p) { return pairs(p.particles.vx, p.particles.vy); },
                             "(N, 2) float64 peculiar velocities (a copy; views: vx, vy)")
      .def_property_readonly("x", [](py::object self) { return grain_view(self.cast<const Packing&>().particles.x, self); },
                             "(N,) float64 view of the x of the centres")
      .def_property_readonly("y", [](py::object self) { return grain_view(self.cast<const Packing&>().particles.y, self); })
      .def_property_readonly("radii", [](py::object self) { return grain_view(self.cast<const Packing&>().particles.radius, self); },
                             "(N,) float64 view of the radii")
      .def_property_readonly("vx", [](py::object self) { return grain_view(self.cast<const Packing&>().particles.vx, self); })
      .def_property_readonly("vy", [](py::object self) { return grain_view(self.cast<const Packing&>().particles.vy, self); })
      .def_property_readonly("omega", [](py::object self) { return grain_view(self.cast<const Packing&>().particles.omega, self); },
                             "(N,) float64 view of the angular velocities (counter-clockwise)")
      .def_property_readonly("contacts", [](py::object self) { return contact_columns(self.cast<const Packing&>(), self); },
                             "views of the contact list: a, b (int32), n, l (M, 2), gap, fn, ft "
                             "(float64); force on b = fn n + ft t, t = (-ny, nx)")
      .def_property_readonly("mu", [](const Packing& p) { return p.meta.contact.mu; })
      .def_property_readonly("P_ext", [](const Packing& p) { return p.meta.contact.P_ext; })
      .def_property_readonly("F0", &Packing::force_unit, "force unit 2 R_avg P_ext")
      .def_property_readonly("phi", &Packing::packing_fraction)
      .def_property_readonly("seed", [](const Packing& p) { return p.meta.seed; })
      .def_property_readonly("is_static", [](const Packing& p) { return p.state.is_static; })
      .def_property_readonly("command", [](const Packing& p) { return p.meta.command; })
      .def_property_readonly("program_version", [](const Packing& p) { return p.meta.program_version; })
      .def_property_readonly("settings", [](const Packing& p) {
        return py::module_::import("json").attr("loads")(p.meta.settings.dump());
      }, "the compaction settings recorded in meta.json (a dict)")
      .def("write", [](const Packing& p, const std::filesystem::path& dir) { write_packing(dir, p); },
           py::arg("dir"), py::call_guard<py::gil_scoped_release>(),
           "write the packing directory (meta.json, particles.csv, contacts.csv), atomically")
      .def("__repr__", [](const Packing& p) {
        return "<unjam.Packing N=" + std::to_string(p.size()) + " contacts=" +
               std::to_string(p.contacts.size()) + " mu=" + py::str(py::float_(p.meta.contact.mu)).cast<std::string>() + ">";
      });

  m.def("read_packing", &read_packing, py::arg("dir"), py::call_guard<py::gil_scoped_release>(),
        "read and check a packing directory written by `unjam pack` or Packing.write");
}

}  // namespace unjam::python
