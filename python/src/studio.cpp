// The studio's state without a page (docs/python.md "Studio", docs/studio.md): a design file held
// open, edits by key path, the live figures as `fivebar studio` computes them, and a save through
// the design-edit API that shows its diff first. The same library calls as the server
// (fivebar/studio.hpp); no HTTP, no widget.
#include <array>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.hpp"
#include "fivebar/error.hpp"
#include "fivebar/scene.hpp"
#include "fivebar/studio.hpp"

namespace fivebar::python {

namespace {

/// A Studio and its edits (the page's state: key path -> value, in the order first set).
class StudioSession {
 public:
  explicit StudioSession(const std::string& file) : studio_(file, validate_products) {}

  void set(const std::string& key, const std::variant<double, std::string>& value) {
    for (FileEdit& e : edits_) {
      if (e.key == key) {
        e.value = value;
        return;
      }
    }
    edits_.push_back({key, value});
  }
  void unset(const std::string& key) { std::erase_if(edits_, [&](const FileEdit& e) { return e.key == key; }); }
  void clear() { edits_.clear(); }

  py::dict edits() const {
    py::dict d;
    for (const FileEdit& e : edits_) {
      if (std::holds_alternative<double>(e.value)) {
        d[py::str(e.key)] = std::get<double>(e.value);
      } else {
        d[py::str(e.key)] = std::get<std::string>(e.value);
      }
    }
    return d;
  }

  /// The figures a drag of the page redraws (regions, coverage, poses, priority rule, tolerance)
  /// or, with `full`, the sampled ones too; the edited file loaded with every rule of the loader.
  py::object figures(const std::optional<std::string>& station, bool full, const std::optional<std::array<double, 2>>& lower,
                     const std::optional<std::array<double, 2>>& upper) {
    const Design d = studio_.design(edits_);
    const std::string name = station.value_or(d.stations.empty() ? std::string() : d.stations.front().name);
    StudioCursor cursor;
    if (lower) cursor.lower = Vec2((*lower)[0], (*lower)[1]);
    if (upper) cursor.upper = Vec2((*upper)[0], (*upper)[1]);
    return to_python(studio_figures(d, name, cursor, full ? StudioFigures::full : StudioFigures::live, &cache_));
  }

  py::object pattern(const std::string& kind, const std::optional<std::string>& station) const {
    const Design d = studio_.design(edits_);
    return to_python(studio_pattern(d, station.value_or(d.stations.empty() ? std::string() : d.stations.front().name), kind));
  }

  py::object preview() const { return to_python(studio_.preview(edits_)); }

  /// Writes the edits (the diff of preview()) unless the file changed on disk since it was read.
  py::object save() {
    Json diff = studio_.preview(edits_);
    const Studio::SaveStatus st = studio_.save(edits_, studio_.text_sha256());
    diff["saved"] = st == Studio::SaveStatus::saved;
    if (st == Studio::SaveStatus::saved) {
      edits_.clear();
    } else {
      diff["reason"] = "the file changed on disk since it was read: nothing written (reload() reads it again)";
    }
    return to_python(diff);
  }

  void reload() {
    studio_.reload();
    edits_.clear();
  }

  std::string file() const { return studio_.file().string(); }
  std::string text() const { return studio_.text(); }
  std::string edited_text() const { return studio_.edited_text(edits_); }
  std::string sha256() const { return studio_.text_sha256(); }

 private:
  Studio studio_;
  std::vector<FileEdit> edits_;
  StudioCache cache_;
};

}  // namespace

void register_studio(py::module_& m) {
  py::class_<StudioSession>(m, "Studio",
                            "A design file open for editing by key path, as in `fivebar studio` (docs/studio.md): the "
                            "figures of the edited state, its patterns, and a save that changes only the edited values.")
      .def(py::init<const std::string&>(), py::arg("file"), "Reads and loads the file (InputError with the loader's message).")
      .def_property_readonly("file", &StudioSession::file)
      .def_property_readonly("text", &StudioSession::text, "The file's text as read (or as last saved).")
      .def_property_readonly("sha256", &StudioSession::sha256)
      .def_property_readonly("edits", &StudioSession::edits, "The edits: key path -> value (mm, deg, or a mode string).")
      .def("set", &StudioSession::set, py::arg("key"), py::arg("value"),
           "Sets the value of a key path (stations.index.mechanisms.lower.links[2]); checked when the figures, the "
           "preview or the save load the edited file.")
      .def("unset", &StudioSession::unset, py::arg("key"))
      .def("clear", &StudioSession::clear, "Drops every edit.")
      .def_property_readonly("edited_text", &StudioSession::edited_text, "The file's text with the edits applied.")
      .def("figures", &StudioSession::figures, py::arg("station") = py::none(), py::arg("full") = false,
           py::arg("lower") = py::none(), py::arg("upper") = py::none(),
           "The studio's figures of one station for the edited state (a dict: regions, coverage as `fivebar coverage "
           "--json`, poses, priority rule, tolerance bands; with full=True the sampled collision map and LCI field), "
           "the tactors at the target centre unless lower / upper give [x, y] mm.")
      .def("pattern", &StudioSession::pattern, py::arg("kind"), py::arg("station") = py::none(),
           "A pattern (stretch, slip, twist, pivot) on the edited state, as `fivebar pattern --json --samples`, with "
           "each sample's linkages (`frames`).")
      .def("preview", &StudioSession::preview, "What save() would write: {file, sha256, changes: [{line, before, after}], valid}.")
      .def("save", &StudioSession::save,
           "Writes the edits into the file (atomically; only the edited values change, comments kept) and returns the "
           "diff with saved=True; saved=False, nothing written, when the file changed on disk since it was read. "
           "InputError for edits the loader refuses.")
      .def("reload", &StudioSession::reload, "Reads the file again from disk and drops the edits.");
}

}  // namespace fivebar::python
