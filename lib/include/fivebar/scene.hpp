#pragma once
/// The scene runner (docs/architecture.md "Products"): a design file is also a scene. run_scene() builds the
/// products the scene asks for (default: every product the file has data for) plus their
/// prerequisites, and nothing else, then writes `<out_root>/<design name>/summary.md`,
/// `summary.json` and `index.html` (summary.md as a page, atomically) listing what was built, what was left out and why, and each
/// product's results.

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

struct SceneOptions {
  /// Output root; the scene writes into `out_root / design.name` (resolve_output_dir rules).
  std::filesystem::path out_root = "outputs";
  /// Overrides the design's `products` list when set (e.g. `fivebar run --products`).
  std::optional<std::vector<std::string>> products;
  /// Progress lines ("building kinematics"), e.g. to stderr; may be empty.
  std::function<void(std::string_view)> progress;
  /// Products built at once (their prerequisites first; docs/architecture.md "Products"); 0: one
  /// per core (std::thread::hardware_concurrency()). The outputs do not depend on it.
  unsigned jobs = 0;
};

/// What happened to one known product.
struct ProductOutcome {
  enum class State { built, left_out };
  std::string name;
  State state = State::left_out;
  bool requested = false;    ///< asked for explicitly (scene list or option), not only implied
  bool prerequisite = false; ///< built because a requested product needs it
  std::string reason;        ///< why it was left out (empty when built)
  bool passed = true;        ///< the product's own check (coverage, collision, ...); true if none
  std::string check;         ///< one line on the check's outcome, may be empty
  Json result;     ///< the product's results (units at the edges)
  std::string title;         ///< heading of its section in summary.md
  std::string markdown;      ///< body of its section in summary.md
  std::vector<std::filesystem::path> files;  ///< files it wrote, relative to the scene directory
  double wall_s = 0.0;       ///< wall time of its build (0 when left out)
};

struct SceneReport {
  std::string design_name;
  std::filesystem::path design_source;
  std::filesystem::path out_dir;  ///< `<out_root>/<name>`
  /// Stations of the design and the mechanisms each contains, in file order.
  std::vector<std::pair<std::string, std::vector<std::string>>> stations;
  bool products_listed = false;   ///< the products came from a list (file or option), not the default
  std::vector<ProductOutcome> products;  ///< every known product, in build order
  std::filesystem::path summary_md;      ///< paths of the two summaries written
  std::filesystem::path summary_json;
  /// summary.md as a page that opens offline, with the products' pictures and the pattern
  /// animations (products/html.hpp)
  std::filesystem::path index_html;

  /// Every built product passed its check and every explicitly requested product was built.
  bool ok() const;
  /// Names of requested products that could not be built.
  std::vector<std::string> missing() const;
  /// The summary.json document.
  Json to_json() const;
  /// The summary.md text.
  std::string to_markdown() const;
};

/// Product names a scene may list, in build order (lib/src/products/products.def).
const std::vector<std::string>& known_products();
/// Checks a design's `products:` list against known_products() (a DesignRule): ValidationError
/// naming the entry ("products[1] = 'nope': unknown product (known: ...)").
void validate_products(const Design& design);
/// load_design() with validate_products(): what the command line loads, a scene being any design.
Design load_scene(const std::filesystem::path& path);
/// Same, from text; `origin` names the source in messages.
Design load_scene_from_string(const std::string& text, const std::string& origin);

/// Re-checks a design a study proposes (the optimiser's chosen design) with the exact checking
/// products it has the data for (coverage at its full sampling; collision and patterns when it has
/// their sections and a station with both mechanisms), as a scene into `out_root / design.name`.
SceneReport check_design(const Design& design, const std::filesystem::path& out_root);

/// Runs a scene. Throws InputError for an unknown product name in `options.products` or an output
/// directory escaping the root; IoError when the output cannot be written. A product that
/// cannot be built (missing data or tool) is not an exception: it is reported as left out.
SceneReport run_scene(const Design& design, const SceneOptions& options = {});

}  // namespace fivebar
