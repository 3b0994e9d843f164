// The names of the products (products.def) and the check of a scene's `products:` list: above the
// design, which knows no product (fivebar/design.hpp DesignRule), so that adding a product
// recompiles neither the design model nor its loader.
#include <algorithm>

#include "design/design_keys.hpp"
#include "fivebar/scene.hpp"

namespace fivebar {

const std::vector<std::string>& known_products() {
  static const std::vector<std::string> names{
#define FIVEBAR_PRODUCT(name) #name,
#include "products/products.def"
#undef FIVEBAR_PRODUCT
  };
  return names;
}

void validate_products(const Design& design) {
  if (!design.products) return;
  const auto& known = known_products();
  for (std::size_t i = 0; i < design.products->size(); ++i) {
    const std::string& product = (*design.products)[i];
    if (std::find(known.begin(), known.end(), product) != known.end()) continue;
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    throw ValidationError(detail::key_index("products", i),
                          "= " + detail::quoted(product) + ": unknown product (known: " + list + ")");
  }
}

Design load_scene(const std::filesystem::path& path) { return load_design(path, validate_products); }

Design load_scene_from_string(const std::string& text, const std::string& origin) {
  return load_design_from_string(text, origin, validate_products);
}

}  // namespace fivebar
