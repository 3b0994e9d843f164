// The Python module fivebar._fivebar (docs/python.md): exceptions, the design model and the
// helpers the other binding sources share. The package fivebar/__init__.py wraps it.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <chrono>
#include <exception>
#include <thread>

#include "bindings.hpp"
#include "fivebar/io.hpp"
#include "fivebar/version.hpp"

namespace fivebar::python {

namespace {

// The Python exception types (fivebar.InputError(ValueError), fivebar.IoError(OSError)) are
// defined by the package in Python and handed over at import (_set_exception_types): they parse
// the file, line and key out of the library's messages. Kept for the life of the interpreter.
PyObject* g_input_error = nullptr;
PyObject* g_io_error = nullptr;

void raise_with_key(PyObject* type, const char* message, const std::string& key) {
  PyObject* args = Py_BuildValue("(s)", message);
  PyObject* instance = args ? PyObject_CallObject(type, args) : nullptr;
  Py_XDECREF(args);
  if (!instance) return;  // the call failed: its error is set
  if (!key.empty()) {
    PyObject* k = PyUnicode_FromString(key.c_str());
    if (k) PyObject_SetAttrString(instance, "rule_key", k);
    Py_XDECREF(k);
  }
  PyErr_SetObject(type, instance);
  Py_DECREF(instance);
}

void translate(std::exception_ptr p) {
  try {
    if (p) std::rethrow_exception(p);
  } catch (const ValidationError& e) {
    raise_with_key(g_input_error ? g_input_error : PyExc_ValueError, e.what(), e.key());
  } catch (const InputError& e) {
    raise_with_key(g_input_error ? g_input_error : PyExc_ValueError, e.what(), "");
  } catch (const IoError& e) {
    PyErr_SetString(g_io_error ? g_io_error : PyExc_OSError, e.what());
  }
  // Everything else falls through to pybind11's own translators: std::exception -> RuntimeError.
}

py::tuple limits_tuple(const Mechanism& m) {
  if (!m.joint_limits) return py::tuple();
  const auto& l = *m.joint_limits;
  return py::make_tuple(py::make_tuple(l[0].lo, l[0].hi), py::make_tuple(l[1].lo, l[1].hi));
}

Vec2 vec2(const std::array<double, 2>& a) { return {a[0], a[1]}; }

/// `n` numbers from a Python sequence, or InputError naming the argument, what it holds and the count.
template <std::size_t n>
std::array<double, n> numbers_of(const py::handle& given, const std::string& what, const char* holds) {
  const bool sequence = py::isinstance<py::sequence>(given) && !py::isinstance<py::str>(given);
  const std::size_t got = sequence ? py::len(given) : 0;
  if (!sequence || got != n) {
    throw InputError(what + ": expected " + std::to_string(n) + " " + holds + ", got " +
                     (sequence ? std::to_string(got) : "a " + std::string(py::str(given.get_type().attr("__name__")))));
  }
  std::array<double, n> out{};
  py::sequence seq = py::reinterpret_borrow<py::sequence>(given);
  for (std::size_t i = 0; i < n; ++i) {
    try {
      out[i] = seq[i].cast<double>();
    } catch (const py::cast_error&) {
      throw InputError(what + "[" + std::to_string(i) + "]: expected a number, got a " +
                       std::string(py::str(py::handle(seq[i]).get_type().attr("__name__"))));
    }
  }
  return out;
}

/// ((a, b), (c, d)) from Python, each pair checked as numbers_of does.
std::array<std::array<double, 2>, 2> pairs_of(const py::object& given, const std::string& what, const char* holds) {
  const bool sequence = py::isinstance<py::sequence>(given) && !py::isinstance<py::str>(given);
  if (!sequence || py::len(given) != 2) {
    throw InputError(what + ": expected 2 " + holds + ", got " +
                     (sequence ? std::to_string(py::len(given)) : "a " + std::string(py::str(given.get_type().attr("__name__")))));
  }
  py::sequence seq = py::reinterpret_borrow<py::sequence>(given);
  return {numbers_of<2>(seq[0], what + "[0]", "numbers"), numbers_of<2>(seq[1], what + "[1]", "numbers")};
}

Mechanism make_mechanism(const std::string& name, const py::object& bases_given, const py::object& links_given,
                         const std::string& working_mode, const std::string& assembly_mode,
                         const py::object& limits_given, double min_lci) {
  const auto bases = pairs_of(bases_given, "bases", "base joints ((x1, y1), (x2, y2)) in mm");
  const auto links = numbers_of<4>(links_given, "links", "lengths (L1, L2, L3, L4) in mm");
  std::optional<std::array<std::array<double, 2>, 2>> limits;
  if (!limits_given.is_none()) limits = pairs_of(limits_given, "joint_limits", "ranges ((lo1, hi1), (lo2, hi2)) in rad");
  Mechanism m;
  m.name = name;
  m.O1 = vec2(bases[0]);
  m.O2 = vec2(bases[1]);
  m.L = links;
  const auto wm = parse_working_mode(working_mode);
  if (!wm) throw InputError("working_mode = \"" + working_mode + "\": must be two signs, e.g. \"-+\"");
  m.working_mode = *wm;
  const auto am = parse_assembly_mode(assembly_mode);
  if (!am) throw InputError("assembly_mode = \"" + assembly_mode + "\": must be \"+\", \"-\" or \"any\"");
  m.assembly_mode = *am;
  if (limits) {
    m.joint_limits = std::array<JointRange, 2>{JointRange{(*limits)[0][0], (*limits)[0][1]},
                                               JointRange{(*limits)[1][0], (*limits)[1][1]}};
  }
  m.min_lci = min_lci;
  m.validate();
  return m;
}

}  // namespace

py::object to_python(const Json& j) {
  switch (j.type()) {
    case Json::value_t::null: return py::none();
    case Json::value_t::boolean: return py::bool_(j.get<bool>());
    case Json::value_t::number_integer: return py::int_(j.get<std::int64_t>());
    case Json::value_t::number_unsigned: return py::int_(j.get<std::uint64_t>());
    case Json::value_t::number_float: return py::float_(j.get<double>());
    case Json::value_t::string: return py::str(j.get_ref<const std::string&>());
    case Json::value_t::array: {
      py::list out;
      for (const Json& v : j) out.append(to_python(v));
      return out;
    }
    case Json::value_t::object: {
      py::dict out;
      for (auto it = j.begin(); it != j.end(); ++it) out[py::str(it.key())] = to_python(it.value());
      return out;
    }
    default: return py::none();
  }
}

py::array_t<double> points_array(const std::vector<Vec2>& points) {
  py::array_t<double> a({py::ssize_t(points.size()), py::ssize_t(2)});
  auto w = a.mutable_unchecked<2>();
  for (std::size_t k = 0; k < points.size(); ++k) {
    w(py::ssize_t(k), 0) = points[k].x();
    w(py::ssize_t(k), 1) = points[k].y();
  }
  return a;
}

py::tuple pair(const Vec2& p) { return py::make_tuple(p.x(), p.y()); }

void Interruptible::run(const std::function<void()>& work) {
  std::exception_ptr failure;
  std::atomic<bool> done{false};
  std::thread worker([&] {
    try {
      work();
    } catch (...) {
      failure = std::current_exception();
    }
    done.store(true);
  });
  std::unique_ptr<py::error_already_set> signal;
  while (!done.load()) {
    {
      py::gil_scoped_release nogil;
      for (int k = 0; k < 50 && !done.load(); ++k) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (!signal && !done.load() && PyErr_CheckSignals() != 0) {
      // Ctrl-C: ask the call to stop at its next check, then wait for it (no thread left behind).
      signal = std::make_unique<py::error_already_set>();
      stop_.store(true);
    }
  }
  {
    py::gil_scoped_release nogil;
    worker.join();
  }
  if (signal) throw std::move(*signal);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (error_) {
      auto e = std::move(error_);
      throw std::move(*e);
    }
  }
  if (failure) std::rethrow_exception(failure);
}

void register_design(py::module_& m) {
  py::class_<Ellipse>(m, "Ellipse", "Filled target ellipse of the fingertip (mm, radians).")
      .def(py::init([](std::array<double, 2> center, std::array<double, 2> axes, double angle) {
             Ellipse e{vec2(center), vec2(axes), angle};
             e.validate();
             return e;
           }),
           py::arg("center"), py::arg("axes"), py::arg("angle") = 0.0,
           "center (x, y) mm; axes: full lengths (mm) along its own x and y; angle: rad, counter-clockwise.")
      .def_property_readonly("center", [](const Ellipse& e) { return pair(e.center); }, "Centre (x, y), mm.")
      .def_property_readonly("axes", [](const Ellipse& e) { return pair(e.axes); }, "Full axis lengths, mm.")
      .def_readonly("angle", &Ellipse::angle, "Rotation, rad, counter-clockwise from +x.")
      .def("boundary_point", [](const Ellipse& e, double t) { return pair(e.boundary_point(t)); }, py::arg("t"),
           "Point (mm) of the boundary at parameter t (rad).")
      .def("to_dict", [](const Ellipse& e) { return to_python(to_json(e)); }, "As the CLI's JSON (mm, deg).")
      .def("__repr__", [](const Ellipse& e) {
        return "Ellipse(center=(" + std::to_string(e.center.x()) + ", " + std::to_string(e.center.y()) + "), axes=(" +
               std::to_string(e.axes.x()) + ", " + std::to_string(e.axes.y()) + "), angle=" + std::to_string(e.angle) +
               ")";
      });

  py::class_<Mechanism>(m, "Mechanism",
                        "One five-bar linkage (docs/design-file.md): base joints O1, O2 (mm), links L1..L4 (mm), "
                        "working and assembly modes, joint limits (rad). Immutable once built.")
      .def(py::init(&make_mechanism), py::arg("name") = "lower", py::arg("bases"), py::arg("links"),
           py::arg("working_mode") = "-+", py::arg("assembly_mode") = "+", py::arg("joint_limits") = py::none(),
           py::arg("min_lci") = 0.0,
           "bases ((x1, y1), (x2, y2)) mm; links (L1, L2, L3, L4) mm; joint_limits ((lo1, hi1), (lo2, hi2)) rad "
           "or None. Raises InputError naming the broken rule.")
      .def_readonly("name", &Mechanism::name)
      .def_property_readonly("O1", [](const Mechanism& x) { return pair(x.O1); }, "First base joint (x, y), mm.")
      .def_property_readonly("O2", [](const Mechanism& x) { return pair(x.O2); }, "Second base joint (x, y), mm.")
      .def_property_readonly("links", [](const Mechanism& x) { return py::make_tuple(x.L[0], x.L[1], x.L[2], x.L[3]); },
                             "(L1, L2, L3, L4), mm.")
      .def_property_readonly("working_mode", [](const Mechanism& x) { return to_string(x.working_mode); },
                             "IK branch, e.g. \"-+\".")
      .def_property_readonly("assembly_mode", [](const Mechanism& x) { return to_string(x.assembly_mode); },
                             "FK branch: \"+\", \"-\" or \"any\".")
      .def_property_readonly("joint_limits", [](const Mechanism& x) -> py::object {
        if (!x.joint_limits) return py::none();
        return limits_tuple(x);
      }, "((lo1, hi1), (lo2, hi2)) rad, counter-clockwise arcs; None without limits.")
      .def_readonly("min_lci", &Mechanism::min_lci)
      .def_property_readonly("length_scale", &Mechanism::length_scale, "Largest length of the linkage, mm.")
      .def("to_dict", [](const Mechanism& x) { return to_python(to_json(x)); }, "As the CLI's JSON (mm, deg).")
      .def("__repr__", [](const Mechanism& x) {
        return "<fivebar.Mechanism " + x.name + " links=(" + std::to_string(x.L[0]) + ", " + std::to_string(x.L[1]) +
               ", " + std::to_string(x.L[2]) + ", " + std::to_string(x.L[3]) + ") mm, working mode " +
               to_string(x.working_mode) + ">";
      });

  py::class_<Station>(m, "Station", "A finger station: its target ellipse and up to two mechanisms.")
      .def_readonly("name", &Station::name)
      .def_readonly("target", &Station::target)
      .def_readonly("lower", &Station::lower, "The lower mechanism, or None.")
      .def_readonly("upper", &Station::upper, "The upper mechanism, or None.")
      .def_property_readonly("mechanisms", [](const Station& s) {
        std::vector<Mechanism> out;
        for (const Mechanism* x : s.mechanisms()) out.push_back(*x);
        return out;
      }, "The mechanisms present, lower first.")
      .def("mechanism", [](const Station& s, const std::string& which) {
        const Mechanism* x = s.mechanism(which);
        if (!x) throw InputError("station '" + s.name + "' has no mechanism '" + which + "'");
        return *x;
      }, py::arg("which"), "The mechanism named \"lower\" or \"upper\" (InputError when absent).")
      .def("__repr__", [](const Station& s) {
        std::string r = "<fivebar.Station " + s.name + ":";
        for (const Mechanism* x : s.mechanisms()) r += " " + x->name;
        return r + ">";
      });

  py::class_<Design, std::shared_ptr<Design>>(m, "Design",
                                              "A validated design file (docs/design-file.md). Immutable: edits "
                                              "return a new Design (with_numbers).")
      .def_static("from_yaml", [](const std::string& text, const std::string& origin) {
        return std::make_shared<Design>(load_design_from_string(text, origin));
      }, py::arg("text"), py::arg("origin") = "<string>",
         "Reads a design from YAML text; `origin` names it in error messages.")
      .def_readonly("name", &Design::name)
      .def_property_readonly("source", [](const Design& d) { return d.source.generic_string(); },
                             "The file it was loaded from ('' when from text).")
      .def_readonly("stations", &Design::stations, "The stations, in file order (copies).")
      .def_readonly("products", &Design::products, "The products the scene lists, or None (every one).")
      .def("station", [](const Design& d, const std::string& name) { return d.require_station(name); },
           py::arg("name"), "The station named `name` (InputError listing the stations when there is none).")
      .def("has_section", [](const Design& d, const std::string& key) { return d.sections.has(key); },
           py::arg("key"), "True when the design has the top-level section `key` (geometry, controller, ...).")
      .def("number", [](const Design& d, const std::string& key) { return design_number(d, key); }, py::arg("key"),
           "The number at a key path in file units (mm, deg), e.g. "
           "\"stations.index.mechanisms.lower.links[2]\" (InputError when the path leads nowhere).")
      .def("with_numbers", [](const Design& d, const std::map<std::string, double>& values) {
        std::vector<std::pair<std::string, double>> v(values.begin(), values.end());
        return std::make_shared<Design>(with_design_numbers(d, v));
      }, py::arg("values"),
         "A new design with the numbers at the key paths replaced (file units); every rule of a design file "
         "applies (InputError naming the key otherwise).")
      .def("to_yaml", [](const Design& d) { return to_yaml(d); },
           "The design as a design file (YAML) that from_yaml() reads back to an equal design.")
      .def("__repr__", [](const Design& d) {
        std::string r = "<fivebar.Design " + d.name + ":";
        for (const Station& s : d.stations) r += " " + s.name;
        return r + ">";
      });

  m.def("load", [](const std::filesystem::path& path) { return std::make_shared<Design>(load_design(path)); },
        py::arg("path"),
        "Loads and validates a design file. Raises fivebar.InputError naming the file, line and key.");
  m.def("version", [] { return std::string(version()); }, "The library's version.");
  m.def("_set_exception_types", [](py::object input_error, py::object io_error) {
    g_input_error = input_error.release().ptr();
    g_io_error = io_error.release().ptr();
  });
}

}  // namespace fivebar::python

PYBIND11_MODULE(_fivebar, m) {
  m.doc() = "fivebar: five-bar haptic device design (C++ library bindings; see the package fivebar).";
  pybind11::register_exception_translator(&fivebar::python::translate);
  fivebar::python::register_design(m);
  fivebar::python::register_kinematics(m);
  fivebar::python::register_studies(m);
  fivebar::python::register_device(m);
  fivebar::python::register_bench(m);
  fivebar::python::register_studio(m);
}
