#pragma once
// The Python module `unjam` (pybind11) over the library: what each binding file registers,
// and the Ctrl-C poll of the long calls. Long calls release the GIL; while they run,
// SignalPoll lets Python's signal handlers run now and then, and a KeyboardInterrupt stops
// the call at the library's next stop point (CompactionHooks, ForceBoundsOptions::should_stop,
// ProbeSettings::cancel inside the running probes).
#include <atomic>
#include <chrono>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <pybind11/pybind11.h>

namespace unjam {
struct CdPathSettings;
struct Packing;
}

namespace unjam::python {

namespace py = pybind11;

void bind_packing(py::module_& m);
void bind_compute(py::module_& m);
void bind_ensemble(py::module_& m);     // unjam.ensemble (python/ensemble.cpp)
void bind_cd_settings(py::module_& m);  // unjam.CdSettings, before bind_compute (its default)
// The cd method's settings from the values of unjam.probe's cd_* keywords, the other fields at
// their defaults (settle_compliance, lost_factor and restart_floor are set through
// cd=unjam.CdSettings only), unchecked: validate(CdPathSettings) checks them.
CdPathSettings cd_settings(const std::string& start, double compliant_start, int softer_starts, long long max_pieces,
                           double accept_residual, double interior_states_pieces, int interior_states_stall,
                           int interior_states_retries, int interior_iterations, double interior_neighbourhood);
// The columns every per-contact result starts with: contact (the index into packing.contacts),
// a, b and the packing's fn of each listed contact, as arrays in the listed order.
py::dict contact_columns(const Packing& p, const std::vector<int>& contacts);
// a and b equal in the fields unjam.CdSettings shows.
bool same_cd_fields(const CdPathSettings& a, const CdPathSettings& b);

// A should_stop hook: from the calling thread only, at most every 0.1 s, it takes the GIL
// and runs PyErr_CheckSignals; after a KeyboardInterrupt (or any error a handler raised)
// it answers true, leaving the Python error set for rethrow_if_interrupted(). Thread safe:
// other threads (the probes of the call's OpenMP team) get the answer of the last check.
class SignalPoll {
 public:
  bool operator()();
  bool interrupted() const { return interrupted_; }
  // With the GIL held: raises the pending Python error if a handler raised one.
  void rethrow_if_interrupted() const;

 private:
  std::thread::id owner_ = std::this_thread::get_id();
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
  std::atomic<bool> interrupted_{false};
};

// A Python callable (progress=) called from the library's threads while a long call has
// released the GIL: each call takes the GIL and passes make()'s value (built under it). Its
// first exception is kept and later calls are skipped; failed() (thread safe) is then true, to
// stop the work as Ctrl-C does, and rethrow_if_failed() raises it once the GIL is held again.
// Made and destroyed with the GIL held.
class Callback {
 public:
  explicit Callback(std::optional<py::function> f) : f_(std::move(f)) {}
  explicit operator bool() const { return f_.has_value(); }
  bool failed() const { return failed_; }
  template <class Make>
  void operator()(Make&& make) {
    if (!f_ || failed_) return;
    py::gil_scoped_acquire gil;
    if (failed_) return;
    try {
      (*f_)(make());
    } catch (py::error_already_set& e) {
      error_ = std::move(e);
      failed_ = true;
    }
  }
  void rethrow_if_failed() {
    if (error_) throw std::move(*error_);
  }

 private:
  std::optional<py::function> f_;
  std::atomic<bool> failed_{false};
  std::optional<py::error_already_set> error_;
};

// Sets the OpenMP thread count of the calling thread for one call (0: leave it), and puts
// the previous count back.
class ThreadCount {
 public:
  explicit ThreadCount(int threads);
  ~ThreadCount();
  ThreadCount(const ThreadCount&) = delete;
  ThreadCount& operator=(const ThreadCount&) = delete;

 private:
  int previous_;
};

}  // namespace unjam::python
