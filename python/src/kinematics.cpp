// Kinematics from Python (docs/python.md "Kinematics"): the scalar solvers returning Pose objects,
// and the batch kernels of fivebar/kinematics.hpp on NumPy arrays: float64 C-contiguous inputs are
// read in place, outputs may be written into arrays the caller gives (`out=`), the GIL is released
// while the kernel runs, and every element has a status (uint8, fivebar.Status), never NaN.

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>

#include "bindings.hpp"
#include "fivebar/kinematics.hpp"

namespace fivebar::python {

namespace {

/// A float64 input of a batch: the caller's array itself when it is a C-contiguous float64
/// ndarray, else a C-contiguous float64 copy of a non-contiguous float64 array or of a list;
/// TypeError for an ndarray of another dtype (no silent conversion of float32 or integers).
struct Input {
  py::array array;
  const double* data = nullptr;
  std::size_t n = 0;
};

Input input(const py::handle& obj, const char* name) {
  Input in;
  if (py::isinstance<py::array>(obj)) {
    auto a = py::reinterpret_borrow<py::array>(obj);
    if (!py::isinstance<py::array_t<double>>(a)) {
      throw py::type_error(std::string(name) + ": dtype " + py::str(a.dtype()).cast<std::string>() +
                           ", expected float64 (convert with .astype(numpy.float64))");
    }
    in.array = (a.flags() & py::array::c_style) ? a : py::array(py::array_t<double, py::array::c_style>::ensure(a));
  } else {
    auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
    if (!a) {
      PyErr_Clear();
      throw py::type_error(std::string(name) + ": expected a float64 array or a sequence of numbers");
    }
    in.array = a;
  }
  in.data = static_cast<const double*>(in.array.data());
  in.n = std::size_t(in.array.size());
  return in;
}

std::vector<py::ssize_t> shape_of(const py::array& a) { return std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()); }

void same_shape(const Input& a, const char* an, const Input& b, const char* bn) {
  if (shape_of(a.array) != shape_of(b.array)) {
    throw py::value_error(std::string("shape mismatch: ") + an + " has shape " +
                          py::str(py::tuple(py::cast(shape_of(a.array)))).cast<std::string>() + ", " + bn + " has " +
                          py::str(py::tuple(py::cast(shape_of(b.array)))).cast<std::string>());
  }
}

/// Index of the first non-finite value, or n. The common case (all finite) is one pass that the
/// compiler vectorises; the index is looked for only when that pass finds one.
std::size_t first_non_finite(const double* x, std::size_t n) {
  // NaN and infinities are the doubles whose exponent bits are all set: an OR over integer
  // compares, which vectorises (a floating-point sum would be one long dependency chain).
  constexpr std::uint64_t kExponent = 0x7ff0000000000000ULL;
  std::uint64_t any = 0;
  for (std::size_t k = 0; k < n; ++k) {
    std::uint64_t bits;
    std::memcpy(&bits, x + k, sizeof bits);
    any |= std::uint64_t((bits & kExponent) == kExponent);
  }
  if (any == 0) return n;
  for (std::size_t k = 0; k < n; ++k) {
    if (!std::isfinite(x[k])) return k;
  }
  return n;
}

/// An output array: the caller's (checked: dtype, C-contiguous, writeable, shape) or a new one.
template <class T>
py::array_t<T> output(const py::object& given, const std::vector<py::ssize_t>& shape, const char* name) {
  if (given.is_none()) return py::array_t<T>(shape);
  if (!py::isinstance<py::array_t<T, py::array::c_style>>(given)) {
    throw py::type_error(std::string("out: ") + name + " must be a C-contiguous numpy array of dtype " +
                         py::str(py::dtype::of<T>()).cast<std::string>());
  }
  auto a = py::reinterpret_borrow<py::array_t<T>>(given);
  if (!a.writeable()) throw py::value_error(std::string("out: ") + name + " is read-only");
  if (shape_of(a) != shape) {
    throw py::value_error(std::string("out: ") + name + " has shape " + py::str(py::tuple(py::cast(shape_of(a)))).cast<std::string>() +
                          ", the inputs " + py::str(py::tuple(py::cast(shape))).cast<std::string>());
  }
  return a;
}

std::vector<py::object> out_tuple(const py::object& out, std::size_t count) {
  std::vector<py::object> o(count, py::none());
  if (out.is_none()) return o;
  if (!py::isinstance<py::tuple>(out) && !py::isinstance<py::list>(out)) {
    throw py::type_error("out: expected a tuple of " + std::to_string(count) + " arrays");
  }
  auto seq = py::reinterpret_borrow<py::sequence>(out);
  if (seq.size() != count) throw py::value_error("out: expected " + std::to_string(count) + " arrays, got " + std::to_string(seq.size()));
  for (std::size_t k = 0; k < count; ++k) o[k] = seq[k];
  return o;
}

template <class T>
std::span<T> span_of(py::array_t<T>& a) {
  return {a.mutable_data(), std::size_t(a.size())};
}
std::span<Status> status_span(py::array_t<std::uint8_t>& a) {
  static_assert(sizeof(Status) == sizeof(std::uint8_t));
  return {reinterpret_cast<Status*>(a.mutable_data()), std::size_t(a.size())};
}

/// ValueError naming the first non-finite value of a or b, when ka < a.n or kb < b.n.
void raise_non_finite(const Input& a, const char* an, std::size_t ka, const Input& b, const char* bn, std::size_t kb) {
  for (auto [k, in, name] : {std::tuple{ka, &a, an}, std::tuple{kb, &b, bn}}) {
    if (k < in->n) {
      throw py::value_error(std::string(name) + " holds " + (std::isnan(in->data[k]) ? "NaN" : "an infinity") +
                            " at flat index " + std::to_string(k) + ": every value must be finite");
    }
  }
}

/// Checks both inputs for NaN and infinity (without the GIL); ValueError naming the first.
void check_finite(const Input& a, const char* an, const Input& b, const char* bn) {
  std::size_t ka = 0, kb = 0;
  {
    py::gil_scoped_release nogil;
    ka = first_non_finite(a.data, a.n);
    kb = first_non_finite(b.data, b.n);
  }
  raise_non_finite(a, an, ka, b, bn, kb);
}

/// Elements per block of a checked batch: the inputs' block is checked while it is in cache, then
/// the kernel reads it from there (no second pass over arrays larger than the cache).
constexpr std::size_t kCheckBlock = 8192;

using Kernel2x2 = void (*)(const Mechanism&, std::span<const double>, std::span<const double>, std::span<double>,
                           std::span<double>, std::span<Status>);

py::tuple batch2(const Mechanism& m, const py::object& a_obj, const char* an, const py::object& b_obj, const char* bn,
                 const py::object& out, const char* on1, const char* on2, Kernel2x2 kernel) {
  const Input a = input(a_obj, an);
  const Input b = input(b_obj, bn);
  same_shape(a, an, b, bn);
  const auto shape = shape_of(a.array);
  const auto o = out_tuple(out, 3);
  auto r1 = output<double>(o[0], shape, on1);
  auto r2 = output<double>(o[1], shape, on2);
  auto st = output<std::uint8_t>(o[2], shape, "status");
  // Block by block: a non-finite input stops the batch there (the outputs before it written).
  std::size_t ka = a.n, kb = b.n;
  {
    py::gil_scoped_release nogil;
    const auto x1 = span_of(r1), x2 = span_of(r2);
    const auto s = status_span(st);
    for (std::size_t first = 0; first < a.n; first += kCheckBlock) {
      const std::size_t n = std::min(kCheckBlock, a.n - first);
      const std::size_t ba = first_non_finite(a.data + first, n), bb = first_non_finite(b.data + first, n);
      if (ba < n || bb < n) {
        if (ba < n) ka = first + ba;
        if (bb < n) kb = first + bb;
        break;
      }
      kernel(m, {a.data + first, n}, {b.data + first, n}, x1.subspan(first, n), x2.subspan(first, n),
             s.subspan(first, n));
    }
  }
  raise_non_finite(a, an, ka, b, bn, kb);
  return py::make_tuple(r1, r2, st);
}

void fk_kernel(const Mechanism& m, std::span<const double> t1, std::span<const double> t2, std::span<double> x,
               std::span<double> y, std::span<Status> s) {
  fk_batch(m, t1, t2, x, y, s);
}
void ik_kernel(const Mechanism& m, std::span<const double> x, std::span<const double> y, std::span<double> t1,
               std::span<double> t2, std::span<Status> s) {
  ik_batch(m, x, y, t1, t2, s);
}

double finite(double v, const char* name) {
  if (!std::isfinite(v)) throw py::value_error(std::string(name) + " = " + std::to_string(v) + ": must be finite");
  return v;
}

AssemblyMode branch_of(const Mechanism& m, const std::optional<std::string>& branch) {
  if (!branch) return m.assembly_mode;
  const auto b = parse_assembly_mode(*branch);
  if (!b) throw InputError("branch = \"" + *branch + "\": must be \"+\", \"-\" or \"any\"");
  return *b;
}

}  // namespace

void register_kinematics(py::module_& m) {
  py::enum_<Status>(m, "Status", "Outcome of a kinematic evaluation; status arrays hold these values as uint8.")
      .value("ok", Status::ok)
      .value("unreachable", Status::unreachable)
      .value("singular_type1", Status::singular_type1)
      .value("singular_type2", Status::singular_type2);

  py::class_<Pose>(m, "Pose",
                   "A configuration of a mechanism and its local properties (mm, rad). Geometric fields are zero "
                   "when status is unreachable; never NaN.")
      .def_readonly("status", &Pose::status)
      .def_readonly("theta1", &Pose::theta1, "Motor angle at O1, rad.")
      .def_readonly("theta2", &Pose::theta2, "Motor angle at O2, rad.")
      .def_property_readonly("A1", [](const Pose& p) { return pair(p.A1); }, "Elbow 1 (x, y), mm.")
      .def_property_readonly("A2", [](const Pose& p) { return pair(p.A2); }, "Elbow 2 (x, y), mm.")
      .def_property_readonly("P", [](const Pose& p) { return pair(p.P); }, "Tactor point (x, y), mm.")
      .def_property_readonly("mode", [](const Pose& p) { return mode_string(p.mode); },
                             "Realised working mode, e.g. \"-+\" (\"0\" on a type I singularity).")
      .def_readonly("assembly", &Pose::assembly, "Realised assembly sign: +1, -1 or 0 on type II.")
      .def_property_readonly("J", [](const Pose& p) { return Eigen::Matrix2d(p.J); }, "Jacobian dP/dtheta, mm/rad (2x2).")
      .def_readonly("jacobian_valid", &Pose::jacobian_valid)
      .def_readonly("lci", &Pose::lci, "1/cond(J) in [0, 1]; 0 at any singularity.")
      .def_readonly("force_capability", &Pose::force_capability, "1/sigma_max(J), N per N*mm.")
      .def_readonly("transmission", &Pose::transmission, "Angles at elbow 1, elbow 2, tactor, rad.")
      .def_readonly("type1_sin", &Pose::type1_sin)
      .def_readonly("type2_sin", &Pose::type2_sin)
      .def_readonly("type1_distance_mm", &Pose::type1_distance_mm)
      .def_readonly("closure_error_mm", &Pose::closure_error_mm)
      .def_readonly("within_joint_limits", &Pose::within_joint_limits)
      .def("to_dict", [](const Pose& p) { return to_python(to_json(p)); },
           "As the CLI's JSON (mm, deg; null fields when unreachable).")
      .def("__repr__", [](const Pose& p) {
        return "Pose(status=" + std::string(to_string(p.status)) + ", theta=(" + std::to_string(p.theta1) + ", " +
               std::to_string(p.theta2) + ") rad, P=(" + std::to_string(p.P.x()) + ", " + std::to_string(p.P.y()) +
               ") mm, lci=" + std::to_string(p.lci) + ")";
      });

  auto mech = py::reinterpret_borrow<py::class_<Mechanism>>(m.attr("Mechanism"));
  mech.def("fk", [](const Mechanism& x, double t1, double t2, const std::optional<std::string>& branch) {
        return fk(x, finite(t1, "theta1"), finite(t2, "theta2"), branch_of(x, branch));
      }, py::arg("theta1"), py::arg("theta2"), py::arg("branch") = py::none(),
      "Forward kinematics at motor angles (rad) on the design's assembly branch (or \"+\", \"-\", \"any\").")
      .def("fk_all", [](const Mechanism& x, double t1, double t2) {
        const auto p = fk_all(x, finite(t1, "theta1"), finite(t2, "theta2"));
        return std::vector<Pose>(p.begin(), p.end());
      }, py::arg("theta1"), py::arg("theta2"), "Both assembly branches, \"+\" then \"-\".")
      .def("ik", [](const Mechanism& x, double px, double py_, const std::optional<std::string>& mode) {
        const Vec2 P(finite(px, "x"), finite(py_, "y"));
        if (!mode) return ik(x, P);
        const auto wm = parse_working_mode(*mode);
        if (!wm) throw InputError("mode = \"" + *mode + "\": must be two signs, e.g. \"-+\"");
        return ik(x, P, *wm);
      }, py::arg("x"), py::arg("y"), py::arg("mode") = py::none(),
      "Inverse kinematics at the tactor point (mm) in the working mode (or the given one).")
      .def("ik_all", [](const Mechanism& x, double px, double py_) {
        const auto p = ik_all(x, Vec2(finite(px, "x"), finite(py_, "y")));
        return std::vector<Pose>(p.begin(), p.end());
      }, py::arg("x"), py::arg("y"), "All four working modes, in the order \"++\", \"+-\", \"-+\", \"--\".")
      .def("fk_batch", [](const Mechanism& x, const py::object& t1, const py::object& t2, const py::object& out) {
        return batch2(x, t1, "theta1", t2, "theta2", out, "x", "y", &fk_kernel);
      }, py::arg("theta1"), py::arg("theta2"), py::kw_only(), py::arg("out") = py::none(),
      "FK of arrays of motor angles (rad, float64, same shape) -> (x, y, status): mm, mm, uint8. "
      "out=(x, y, status) writes into the caller's arrays. The GIL is released.")
      .def("ik_batch", [](const Mechanism& x, const py::object& px, const py::object& py_, const py::object& out) {
        return batch2(x, px, "x", py_, "y", out, "theta1", "theta2", &ik_kernel);
      }, py::arg("x"), py::arg("y"), py::kw_only(), py::arg("out") = py::none(),
      "IK of arrays of tactor points (mm) -> (theta1, theta2, status): rad, rad, uint8.")
      .def("lci_batch", [](const Mechanism& x, const py::object& px_obj, const py::object& py_obj, const py::object& out) {
        const Input a = input(px_obj, "x");
        const Input b = input(py_obj, "y");
        same_shape(a, "x", b, "y");
        const auto shape = shape_of(a.array);
        const auto o = out_tuple(out, 2);
        auto l = output<double>(o[0], shape, "lci");
        auto st = output<std::uint8_t>(o[1], shape, "status");
        check_finite(a, "x", b, "y");
        {
          py::gil_scoped_release nogil;
          lci_batch(x, {a.data, a.n}, {b.data, b.n}, span_of(l), status_span(st));
        }
        return py::make_tuple(l, st);
      }, py::arg("x"), py::arg("y"), py::kw_only(), py::arg("out") = py::none(),
      "LCI at arrays of tactor points (mm) in the working mode -> (lci, status); 0 where not ok.")
      .def("jacobian_batch", [](const Mechanism& x, const py::object& t1_obj, const py::object& t2_obj) {
        const Input a = input(t1_obj, "theta1");
        const Input b = input(t2_obj, "theta2");
        same_shape(a, "theta1", b, "theta2");
        auto shape = shape_of(a.array);
        auto st = py::array_t<std::uint8_t>(shape);
        shape.push_back(2);
        shape.push_back(2);
        auto J = py::array_t<double>(shape);
        check_finite(a, "theta1", b, "theta2");
        {
          py::gil_scoped_release nogil;
          double* j = J.mutable_data();
          std::uint8_t* s = st.mutable_data();
          const std::int64_t n = std::int64_t(a.n);
#pragma omp parallel for schedule(static) if (n > 4096)
          for (std::int64_t k = 0; k < n; ++k) {
            const Pose p = fk(x, a.data[k], b.data[k]);
            const bool valid = p.jacobian_valid;
            j[4 * k + 0] = valid ? p.J(0, 0) : 0.0;
            j[4 * k + 1] = valid ? p.J(0, 1) : 0.0;
            j[4 * k + 2] = valid ? p.J(1, 0) : 0.0;
            j[4 * k + 3] = valid ? p.J(1, 1) : 0.0;
            s[k] = std::uint8_t(p.status);
          }
        }
        return py::make_tuple(J, st);
      }, py::arg("theta1"), py::arg("theta2"),
      "Jacobians dP/dtheta (mm/rad) at arrays of motor angles (rad) -> (J[..., 2, 2], status); zero where "
      "the Jacobian does not exist (unreachable, type II).");
}

}  // namespace fivebar::python
