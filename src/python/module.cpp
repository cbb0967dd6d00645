// PYBIND11_MODULE(unjam): the library's types and calls for Python (README, "Python").
#include <omp.h>

#include <pybind11/numpy.h>

#include "python/bindings.hpp"
#include "unjam/packing/packing.hpp"
#include "unjam/core/error.hpp"
#include "unjam/core/version.hpp"

namespace unjam::python {

bool SignalPoll::operator()() {
  if (interrupted_) return true;
  if (std::this_thread::get_id() != owner_) return false;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_ < std::chrono::milliseconds(100)) return false;
  last_ = now;
  py::gil_scoped_acquire gil;
  interrupted_ = PyErr_CheckSignals() != 0;
  return interrupted_;
}

void SignalPoll::rethrow_if_interrupted() const {
  if (interrupted_) throw py::error_already_set();
}

ThreadCount::ThreadCount(int threads) : previous_(omp_get_max_threads()) {
  if (threads < 0) throw Error("threads must be >= 0 (0: all cores)");
  if (threads > 0) omp_set_num_threads(threads);
}

ThreadCount::~ThreadCount() { omp_set_num_threads(previous_); }

py::dict contact_columns(const Packing& p, const std::vector<int>& contacts) {
  const auto n = static_cast<py::ssize_t>(contacts.size());
  py::array_t<int> contact(n), a(n), b(n);
  py::array_t<double> fn(n);
  for (py::ssize_t k = 0; k < n; ++k) {
    const Contact& c = p.contacts[contacts[k]];
    contact.mutable_at(k) = contacts[k];
    a.mutable_at(k) = c.a;
    b.mutable_at(k) = c.b;
    fn.mutable_at(k) = c.fn;
  }
  py::dict d;
  d["contact"] = contact;
  d["a"] = a;
  d["b"] = b;
  d["fn"] = fn;
  return d;
}

}  // namespace unjam::python

PYBIND11_MODULE(unjam, m) {
  namespace py = pybind11;
  m.doc() =
      "unjam: mechanics of jammed packings of rigid frictional disks (the library behind the "
      "`unjam` tool). Units and sign conventions: docs/packing-format.md.";
  m.attr("__version__") = unjam::kVersion;
  // unjam::Error (bad input, unreadable file, invalid parameter) arrives as unjam.Error, a
  // ValueError, with the library's message.
  py::register_exception<unjam::Error>(m, "Error", PyExc_ValueError);
  unjam::python::bind_packing(m);
  unjam::python::bind_cd_settings(m);
  unjam::python::bind_compute(m);
  unjam::python::bind_ensemble(m);
}
