// fivebar::fivebar from an install prefix: the installed showcase design's index station covers its
// target (the paper's claim, docs/tour.md "coverage"), a file written through the library's atomic
// writer (fivebar/io.hpp) reads back, and the library's version is the package's.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "fivebar/coverage/coverage.hpp"
#include "fivebar/design.hpp"
#include "fivebar/io.hpp"
#include "fivebar/version.hpp"

int main(int argc, char** argv) {
  const fivebar::Design d = fivebar::load_design(SHARE_DIR "/designs/iros2022.yaml");
  const fivebar::StationCoverage c = fivebar::station_coverage(d.require_station("index"));
  if (!c.covered()) {
    std::fprintf(stderr, "full: the index station does not cover its target\n");
    return 1;
  }
  const std::filesystem::path file = std::filesystem::path(argc > 1 ? argv[1] : ".") / "written.txt";
  fivebar::write_file_atomic(file, "fivebar\n");
  std::ifstream in(file);
  std::stringstream back;
  back << in.rdbuf();
  if (back.str() != "fivebar\n") {
    std::fprintf(stderr, "full: %s reads back as '%s'\n", file.c_str(), back.str().c_str());
    return 1;
  }
  if (std::string(fivebar::version()) != PACKAGE_VERSION) {
    std::fprintf(stderr, "full: library %s, package %s\n", std::string(fivebar::version()).c_str(), PACKAGE_VERSION);
    return 1;
  }
  std::printf("full: index covered, version %s\n", PACKAGE_VERSION);
  return 0;
}
