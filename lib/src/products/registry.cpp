#include "products/product.hpp"

namespace fivebar::products {

const std::vector<Product>& registry() {
  static const std::vector<Product> entries = {
#define FIVEBAR_PRODUCT(name) name##_product(),
#include "products/products.def"
#undef FIVEBAR_PRODUCT
  };
  return entries;
}

const Product* find_product(std::string_view name) {
  for (const Product& p : registry()) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

const Json* Context::result_of(std::string_view name) const {
  const auto it = results.find(std::string(name));
  return it == results.end() ? nullptr : &it->second;
}

std::filesystem::path Context::write_file(const std::filesystem::path& relative, std::string_view content) {
  const std::filesystem::path path = dir / relative;
  make_directories(path.parent_path());
  write_file_atomic(path, content);
  record(relative);
  return path;
}

AtomicFile Context::open_file(const std::filesystem::path& relative) {
  const std::filesystem::path path = dir / relative;
  make_directories(path.parent_path());
  return AtomicFile(path);
}

void Context::record(const std::filesystem::path& relative) { files.push_back(relative); }

void Context::say(std::string_view message) const {
  if (progress) progress(message);
}

}  // namespace fivebar::products
