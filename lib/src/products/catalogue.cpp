// The names of the products (products.def), for the design loader, which checks a scene's
// `products:` list without linking the products themselves (they are not in fivebar::core).
#include "fivebar/design.hpp"

namespace fivebar {

const std::vector<std::string>& known_products() {
  static const std::vector<std::string> names{
#define FIVEBAR_PRODUCT(name) #name,
#include "products/products.def"
#undef FIVEBAR_PRODUCT
  };
  return names;
}

}  // namespace fivebar
