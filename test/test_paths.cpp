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
  std::string shared_data;
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
        const std::string data_key = "FIVEBAR_SHARED_DATA_DIR:PATH=";
        Paths found;
        for (std::string line; std::getline(in, line);) {
          if (line.rfind(key, 0) == 0) found.source = line.substr(key.size());
          if (line.rfind(data_key, 0) == 0) found.shared_data = line.substr(data_key.size());
        }
        if (found.source.empty()) fail(cache.string() + " has no CMAKE_HOME_DIRECTORY");
        found.binary = (dir / "fivebar").string();
        return found;
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
const char* shared_data_dir() { return paths().shared_data.c_str(); }

}  // namespace fivebar_test_paths
