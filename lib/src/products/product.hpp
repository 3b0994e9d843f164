#pragma once
/// The product plug-in behind run_scene() (fivebar/scene.hpp; docs/architecture.md "Products").
/// A product is the glue file lib/src/<name>/product.cpp of its study's folder, which defines
/// `Product <name>_product()`: its name, what it needs first, whether a design has the data for it,
/// and how to build it (results, summary section, files). It is registered by one line in
/// products.def, which also gives known_products() its names and the build order.

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/io.hpp"
#include "fivebar/json.hpp"
#include "fivebar/scene.hpp"

namespace fivebar::products {

/// What a product's build() sees and may use.
struct Context {
  const Design& design;
  std::filesystem::path dir;                       ///< the scene's output directory (exists)
  const std::map<std::string, Json>& results;  ///< results of products built so far
  std::function<void(std::string_view)> progress;  ///< may be empty
  std::vector<std::filesystem::path> files;        ///< files written so far, relative to dir
  /// Runs the checking products on another design (a study's proposal): check_design() over the
  /// scene's own product list. Set by the scene runner.
  std::function<SceneReport(const Design&, const std::filesystem::path&)> check_design;

  /// The result of an earlier product (a prerequisite), or nullptr.
  const Json* result_of(std::string_view name) const;
  /// Writes `relative` under dir atomically (creating sub-directories) and records it.
  std::filesystem::path write_file(const std::filesystem::path& relative, std::string_view content);
  /// For streamed files: an AtomicFile at `relative` under dir; after commit(), call record().
  AtomicFile open_file(const std::filesystem::path& relative);
  void record(const std::filesystem::path& relative);
  void say(std::string_view message) const;
};

/// What build() returns.
struct Built {
  Json result;  ///< goes to summary.json under results.<name>
  std::string markdown;   ///< body of the product's section in summary.md (no top heading)
  bool passed = true;     ///< the product's own check; true when it has none
  std::string check;      ///< one line describing the check's outcome
};

struct Product {
  std::string name;                   ///< as in known_products()
  std::string title;                  ///< section heading in summary.md
  std::vector<std::string> prerequisites;  ///< products that must be built first
  /// Products whose results (or files) this one uses when the scene builds them too, without
  /// needing them: it then waits for them (the scene runs independent products in parallel, and
  /// what a product reads must not depend on the timing).
  std::vector<std::string> after;
  /// Rough build time (s) of this product on the showcase, for the scene's scheduler only: it
  /// starts the product heading the longest chain of such times first (the wall times of an earlier
  /// run's summary.json in the output folder replace these when there). Never changes a result.
  double cost_s = 0.1;
  /// Why this design cannot have the product (missing section, no mechanism, tool not
  /// installed), or std::nullopt when it can.
  std::function<std::optional<std::string>(const Design&)> unavailable;
  std::function<Built(Context&)> build;
  /// Reads and checks the product's own input files (a bench file: InputError naming FILE:LINE:
  /// column), called by the scene for every product it will build before the output folder is
  /// created, so that a bad input leaves nothing written (docs/reliability.md). May be empty.
  std::function<void(const Design&)> check_inputs;
  /// One of the exact checks a study's proposed design is re-run through (check_design(): a
  /// design's coverage, collision, patterns), whenever the design has the data for it.
  bool checks_designs = false;
};

/// Product::unavailable for the products that need at least one station with a mechanism.
inline std::optional<std::string> without_mechanisms(const Design& d) {
  for (const Station& s : d.stations)
    if (!s.mechanisms().empty()) return std::nullopt;
  return "no station has a mechanism";
}

/// True when both tactors of `s` are there (the products on a pair: collision, pattern).
inline bool has_pair(const Station& s) { return s.lower.has_value() && s.upper.has_value(); }

/// Product::unavailable for the products on a station's two tactors: they need the design's
/// `geometry:` (`geometry_for` says what for) and a station with both mechanisms.
inline std::optional<std::string> without_pairs(const Design& d, std::string_view geometry_for) {
  if (!d.get<Geometry>()) return "the design has no `geometry:` section (" + std::string(geometry_for) + ")";
  for (const Station& s : d.stations)
    if (has_pair(s)) return std::nullopt;
  return "no station has both a lower and an upper mechanism";
}

/// The controller file (`<design>_controller.json`, relative to the scene's folder) among the
/// files of the `export` product's result, or "" when it wrote none (refused, or not built).
inline std::string exported_controller_json(const Json* export_result) {
  std::string file;
  if (export_result == nullptr || !export_result->contains("files")) return file;
  for (const Json& f : (*export_result)["files"]) {
    const std::string s = f.get<std::string>();
    if (s.size() > 16 && s.compare(s.size() - 16, 16, "_controller.json") == 0) file = s;
  }
  return file;
}

/// Every product, in the order of products.def (the build order).
const std::vector<Product>& registry();
/// run_scene() over a given list of products instead of registry(): the scene knows products only
/// through this list (names, order, prerequisites), which tests extend with throwaway products.
/// Prerequisites must come earlier in the list.
SceneReport run_scene_with(const Design& design, const SceneOptions& options, const std::vector<Product>& registry);
/// check_design() over a given list of products (Product::checks_designs).
SceneReport check_design_with(const Design& design, const std::filesystem::path& out_root,
                              const std::vector<Product>& registry);
/// The entry named `name`, or nullptr when this build does not implement it.
const Product* find_product(std::string_view name);

// --- Entries: one folder each (products.def) --------------------------------------------------
#define FIVEBAR_PRODUCT(name) Product name##_product();
#include "products/products.def"
#undef FIVEBAR_PRODUCT

}  // namespace fivebar::products
