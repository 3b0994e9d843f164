#pragma once
/// The validated design model (docs/design-file.md): stations, their target ellipse and
/// their lower/upper five-bar mechanisms. Lengths in mm, angles in radians inside the library.
/// A Design is built once by load_design() (or by hand followed by validate()) and then only read.

#include <Eigen/Core>

#include <any>
#include <array>
#include <functional>
#include <map>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fivebar/error.hpp"

namespace fivebar {

using Vec2 = Eigen::Vector2d;

/// A validation failure: `key` is the path of the offending value relative to the structure that
/// validated it (e.g. "links[2]"); the loader prefixes the file, line and full key path.
/// `rule` either starts with the value ("= -3 mm: must be > 0", what() = "links[2] = -3 mm: must
/// be > 0") or is a bare rule ("must contain at least one of lower, upper", joined with ": ").
class ValidationError : public InputError {
 public:
  ValidationError(std::string key, const std::string& message)
      : InputError(compose(key, message)), key_(std::move(key)), rule_(message) {}
  const std::string& key() const noexcept { return key_; }
  const std::string& rule() const noexcept { return rule_; }
  /// "key = value: rule" or "key: rule", as what() reads.
  static std::string compose(const std::string& key, const std::string& rule) {
    if (rule.starts_with("= ")) return key + " " + rule;
    return key + ": " + rule;
  }

 private:
  std::string key_;
  std::string rule_;
};

/// Working mode (IK branch): for each leg i the sign of cross(A_i - O_i, P - A_i), +1 or -1.
/// Both elbows outward is "-+" for a lower mechanism and "+-" for an upper one.
struct WorkingMode {
  std::int8_t sign1 = -1;
  std::int8_t sign2 = +1;
  friend bool operator==(const WorkingMode&, const WorkingMode&) = default;
};

/// Parses "+-" style strings; std::nullopt when malformed.
std::optional<WorkingMode> parse_working_mode(std::string_view text);
std::string to_string(WorkingMode mode);
/// The four working modes in the fixed order "++", "+-", "-+", "--".
std::array<WorkingMode, 4> all_working_modes();

/// Assembly mode (FK branch): sign of cross(A2 - A1, P - A1); Any = not restricted.
enum class AssemblyMode : std::int8_t { Minus = -1, Any = 0, Plus = 1 };
std::optional<AssemblyMode> parse_assembly_mode(std::string_view text);
std::string to_string(AssemblyMode mode);

/// Counter-clockwise arc of admissible motor angles from lo to hi (radians).
struct JointRange {
  double lo = 0.0;
  double hi = 0.0;
  /// Width of the arc in (0, 2*pi].
  double span() const;
  /// True when angle (any representative) lies on the arc, within tol radians.
  bool contains(double angle, double tol = 0.0) const;
};

/// One five-bar linkage. O1, O2 base joints; L = {L1, L2, L3, L4} (mm); A_i = O_i + L_i e(theta_i);
/// distal links L3 (from A1) and L4 (from A2) meet at the tactor P.
struct Mechanism {
  std::string name;  ///< "lower" or "upper"
  Vec2 O1{0.0, 0.0};
  Vec2 O2{0.0, 0.0};
  std::array<double, 4> L{0.0, 0.0, 0.0, 0.0};
  WorkingMode working_mode{};
  AssemblyMode assembly_mode = AssemblyMode::Any;
  std::optional<std::array<JointRange, 2>> joint_limits;  ///< radians
  double min_lci = 0.0;                                    ///< usability threshold in [0, 1]

  /// Largest length of the linkage (links and base distance), mm: the scale of every tolerance.
  double length_scale() const;
  /// Throws ValidationError naming the key ("links[2]", "bases[1]", ...) on a broken rule.
  void validate() const;
};

/// Filled target ellipse of the fingertip: centre (mm), full axis lengths (mm), rotation (rad).
struct Ellipse {
  Vec2 center{0.0, 0.0};
  Vec2 axes{0.0, 0.0};  ///< full lengths along its own x and y axes
  double angle = 0.0;   ///< radians, counter-clockwise from +x
  void validate() const;
  /// Point on the boundary at parameter t (radians).
  Vec2 boundary_point(double t) const;
};

/// One finger station: a target ellipse and up to two mechanisms sharing it.
struct Station {
  std::string name;  ///< "index", "thumb", ...
  Ellipse target;
  std::optional<Mechanism> lower;
  std::optional<Mechanism> upper;
  void validate() const;
  /// The mechanisms present, lower first.
  std::vector<const Mechanism*> mechanisms() const;
  const Mechanism* mechanism(std::string_view which) const;
};

/// The optional sections of a design file beside its stations (`geometry:`, `controller:`, ...),
/// held without knowing their types. Each section is a module: a settings type T with
/// `static constexpr std::string_view kKey` (its top-level key) in fivebar/sections/<key>.hpp,
/// and its loader, writer and cross-section rules in lib/src/sections/<key>.cpp
/// (docs/architecture.md "Design sections").
class Sections {
 public:
  /// The section of type T, or nullptr when the design has none.
  template <class T>
  const T* get() const {
    const auto it = items_.find(T::kKey);
    return it == items_.end() ? nullptr : std::any_cast<T>(&it->second);
  }
  template <class T>
  T* get() {
    const auto it = items_.find(T::kKey);
    return it == items_.end() ? nullptr : std::any_cast<T>(&it->second);
  }
  /// Adds or replaces the section of type T; returns the stored copy.
  template <class T>
  T& set(T value) {
    std::any& slot = items_[std::string(T::kKey)];
    slot = std::move(value);
    return *std::any_cast<T>(&slot);
  }
  template <class T>
  void reset() {
    items_.erase(std::string(T::kKey));
  }
  /// True when the design has the section whose top-level key is `key`.
  bool has(std::string_view key) const { return items_.find(key) != items_.end(); }

 private:
  std::map<std::string, std::any, std::less<>> items_;
};

/// A whole design (and scene).
struct Design {
  std::string name;                   ///< used for outputs/<name>/: a safe file name
  std::filesystem::path source;       ///< file it was loaded from (may be empty)
  std::vector<Station> stations;      ///< in file order
  std::optional<std::vector<std::string>> products;  ///< absent: every product the data allows
  Sections sections;                  ///< `geometry:`, `print:`, `controller:`, ... (any subset)

  /// The section of type T (fivebar/sections/<key>.hpp), or nullptr when the file has none.
  template <class T>
  const T* get() const { return sections.get<T>(); }
  template <class T>
  T* get() { return sections.get<T>(); }
  template <class T>
  T& set(T value) { return sections.set(std::move(value)); }
  template <class T>
  void reset() { sections.reset<T>(); }
  template <class T>
  bool has() const { return sections.get<T>() != nullptr; }

  void validate() const;
  /// The station named `name`, or nullptr.
  const Station* station(std::string_view name) const;
  /// The station named `name`; InputError "unknown station 'NAME' in design 'D' (it has: ...)"
  /// listing the design's stations when there is none.
  const Station& require_station(std::string_view name) const;
  /// The stations a whole-station command works on: the one named `name` (as require_station()),
  /// or, for an empty name, every station with a mechanism, in file order.
  std::vector<const Station*> select_stations(std::string_view name) const;
};

/// True when `name` can serve as a design or station name and hence as one path component under
/// outputs/: 1 to 64 characters from [A-Za-z0-9_.-], the first not '.' or '-'.
bool is_safe_name(std::string_view name);

/// The design as a design file (YAML, file units, numbers in shortest round-trip form) that
/// load_design_from_string() reads back to an equal design.
std::string to_yaml(const Design& design);
/// The number at `key`, a key path of the design file in file units (mm, degrees, as
/// docs/design-file.md lists them): "stations.index.mechanisms.lower.links[2]",
/// "stations.index.target.axes[0]", "geometry.link_width", "controller.pid.kp". The path is followed
/// through to_yaml(design), so a key the file leaves at its default is found too. ValidationError
/// naming the key when the path leads nowhere or to something that is not a number.
double design_number(const Design& design, std::string_view key);
/// The design with the numbers at the key paths replaced (file units), read back by the loader:
/// every rule of a design file applies (InputError / ValidationError otherwise).
Design with_design_numbers(const Design& design, const std::vector<std::pair<std::string, double>>& values);
/// Every key path under `prefix` (as design_number() takes them) that leads to a number of
/// to_yaml(design), in file order; empty when the prefix leads nowhere.
std::vector<std::string> design_number_keys(const Design& design, std::string_view prefix);
/// Limits on design files (README "Hardening"), checked before the YAML parser sees the text so
/// that no file can exhaust the stack or the memory: larger files, deeper nesting, bytes that are
/// not UTF-8 or characters YAML forbids (control characters) are refused with an InputError.
inline constexpr std::size_t kMaxDesignFileBytes = std::size_t{1} << 20;  ///< 1 MiB
/// Levels of block indentation, "- " / "? " items and [ { brackets, counted together.
inline constexpr int kMaxDesignNesting = 64;

/// A rule of a layer above the design, checked by the loader after Design::validate(): it throws
/// ValidationError naming the key, which the loader reports with the file and line like its own
/// rules. The scene's product names are one (fivebar/scene.hpp load_scene()): the design itself
/// knows no product.
using DesignRule = std::function<void(const Design&)>;

/// Loads and validates a design file. Throws InputError whose message names the file, line, full
/// key path, value and the rule broken ("designs/x.yaml:12: stations.index.mechanisms.lower.links[2]
/// = -3 mm: must be > 0"); problems of the whole file omit the line ("x.yaml: no such design file").
/// `rule`, when given, is checked too (DesignRule).
Design load_design(const std::filesystem::path& path, const DesignRule& rule = {});
/// Same, from text (for tests and stdin); `origin` names the source in messages.
Design load_design_from_string(const std::string& text, const std::string& origin, const DesignRule& rule = {});

}  // namespace fivebar
