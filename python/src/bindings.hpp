#pragma once
// Shared by the binding sources of the Python module (python/src/): pybind11 stays in these
// translation units only. Units follow the library: mm and radians (docs/python.md).

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/json.hpp"

namespace fivebar::python {

namespace py = pybind11;

void register_design(py::module_& m);
void register_kinematics(py::module_& m);
void register_studies(py::module_& m);
void register_device(py::module_& m);
void register_bench(py::module_& m);
void register_studio(py::module_& m);

/// A JSON document of the library (to_json(...), mm and degrees) as Python dicts, lists and numbers.
py::object to_python(const Json& j);

/// A NumPy array over `data` that keeps `owner` alive (no copy): shape and element type as given.
template <class T, class Owner>
py::array_t<T> view(const std::shared_ptr<Owner>& owner, const T* data, std::vector<py::ssize_t> shape) {
  auto* keep = new std::shared_ptr<const void>(owner);
  py::capsule base(keep, [](void* p) { delete static_cast<std::shared_ptr<const void>*>(p); });
  py::array_t<T> a(std::move(shape), data, base);
  // Views of results are read-only: the result object owns the numbers.
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

/// A float64 array of n x 2 points (copied: Vec2 is not a plain pair of doubles in every layout).
py::array_t<double> points_array(const std::vector<Vec2>& points);
/// (x, y) as a Python tuple.
py::tuple pair(const Vec2& p);

/// Long library calls: runs `work` on a worker thread while the calling thread waits with the GIL
/// released, checking for signals (Ctrl-C) every 50 ms. On a signal `stop` (when the call has
/// one) is set, the worker is waited for, and the Python exception (KeyboardInterrupt) is raised;
/// a Python exception from a progress callback (Progress below) is raised the same way. Library
/// exceptions propagate as themselves (translated to Python's by the module).
class Interruptible {
 public:
  Interruptible() = default;
  /// The flag the library call polls (SweepOptions::stop, OptimizeOptions::stop).
  const std::atomic<bool>* stop() const { return &stop_; }
  bool stopped() const { return stop_.load(); }
  /// Calls `callback(args...)` with the GIL held, from any thread; an exception it raises stops
  /// the call (stop() is set) and is raised when run() returns.
  template <class... Args>
  void call(const py::object& callback, Args&&... args) {
    if (!callback || callback.is_none() || stop_.load()) return;
    py::gil_scoped_acquire gil;
    try {
      callback(std::forward<Args>(args)...);
    } catch (py::error_already_set& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::make_unique<py::error_already_set>(std::move(e));
      stop_.store(true);
    }
  }
  /// Runs `work` (see above). Must be called with the GIL held.
  void run(const std::function<void()>& work);

 private:
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::unique_ptr<py::error_already_set> error_;
};

}  // namespace fivebar::python
