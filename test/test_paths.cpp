// test/test_paths.hpp: the build directory is the nearest ancestor of the running executable that
// holds CMakeCache.txt; the source tree is its CMAKE_HOME_DIRECTORY.
#include "test_paths.hpp"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace fivebar_test_paths {
namespace {

namespace fs = std::filesystem;

struct Paths {
  std::string source;
  std::string binary;
};

[[noreturn]] void fail(const std::string& why) {
  std::fprintf(stderr, "test_paths: %s\n", why.c_str());
  std::abort();
}

const Paths& paths() {
  static const Paths p = [] {
    std::error_code ec;
    fs::path dir = fs::read_symlink("/proc/self/exe", ec).parent_path();
    if (ec) fail("cannot read /proc/self/exe: " + ec.message());
    for (; !dir.empty(); dir = dir.parent_path()) {
      const fs::path cache = dir / "CMakeCache.txt";
      if (fs::exists(cache)) {
        std::ifstream in(cache);
        const std::string key = "CMAKE_HOME_DIRECTORY:INTERNAL=";
        for (std::string line; std::getline(in, line);) {
          if (line.rfind(key, 0) == 0) return Paths{line.substr(key.size()), (dir / "fivebar").string()};
        }
        fail(cache.string() + " has no CMAKE_HOME_DIRECTORY");
      }
      if (dir == dir.root_path()) break;
    }
    fail("no CMakeCache.txt above the test executable");
  }();
  return p;
}

}  // namespace

const char* source_dir() { return paths().source.c_str(); }
const char* fivebar_binary() { return paths().binary.c_str(); }

}  // namespace fivebar_test_paths
