#pragma once
// The base fixture of the tests that run the real `fivebar` binary on the paper's design: a scratch
// directory per test, the binary run in it with a time bound (test/process.hpp, the layer below),
// edited copies of designs/iros2022.yaml and the JSON on stdout. A suite derives its own fixture,
// which keeps only what is specific to it.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "process.hpp"

namespace fivebar::testing {

/// One (from, to) replacement in a copy of the paper's design file.
using Edit = std::pair<std::string, std::string>;

/// A scratch directory per test, the binary run in it, and the paper's design, as is or edited.
class CliTest : public ::testing::Test {
 public:
  /// The source tree (FIVEBAR_SOURCE_DIR, set by test/CMakeLists.txt).
  static inline const fs::path kSource = FIVEBAR_SOURCE_DIR;
  /// The paper's design file; most end-to-end tests run on it or on an edited copy of it.
  static inline const std::string kDesign = (kSource / "designs" / "iros2022.yaml").string();

 protected:
  /// `prefix` names the scratch directory, one per suite, so that a leftover says whose it is.
  explicit CliTest(const std::string& prefix) : scratch_(prefix) {}

  /// Runs the binary in dir_ with `input` on stdin (none: /dev/null); stdin, stdout and stderr pass
  /// through files in dir_ that are gone when it returns. A failure to start or a timeout fails the test.
  Outcome run(const std::vector<std::string>& args, const std::string& input = "") {
    return run_with_env(args, {}, input);
  }
  /// Not stdin: environment variables go through run_with_env() (a braced list would make a string).
  Outcome run(const std::vector<std::string>& args, const std::vector<std::string>& env) = delete;

  /// run() with `env` ("NAME=value" each) set on top of this process's environment.
  Outcome run_with_env(const std::vector<std::string>& args, const std::vector<std::string>& env,
                       const std::string& input = "") {
    fs::path in;
    if (!input.empty()) {
      in = dir_ / ".stdin";
      std::ofstream(in, std::ios::binary) << input;
    }
    // Generous: a sanitized build runs several times slower (FIVEBAR_TEST_CHILD_TIMEOUT_S overrides it).
    Outcome r = ::fivebar::testing::run(FIVEBAR_BINARY, args, dir_, dir_, child_timeout_s(600.0), in, env);
    std::error_code ec;
    if (!in.empty()) fs::remove(in, ec);
    if (!r.spawned) ADD_FAILURE() << "cannot spawn " << FIVEBAR_BINARY;
    if (r.timed_out) ADD_FAILURE() << "fivebar timed out: " << r.err;
    return r;
  }

  /// stdout of `r` as JSON; fails the test unless it is exactly one JSON document.
  static nlohmann::json parse(const Outcome& r) {
    nlohmann::json j;
    EXPECT_NO_THROW(j = nlohmann::json::parse(r.out)) << "stdout is not exactly one JSON document:\n" << r.out;
    return j;
  }

  /// Files and directories under `root`, relative and sorted; unlike ft::tree(), no sizes and no '/'.
  static std::vector<std::string> tree(const fs::path& root) {
    std::vector<std::string> out;
    if (!fs::exists(root)) return out;
    for (const auto& e : fs::recursive_directory_iterator(root)) {
      out.push_back(fs::relative(e.path(), root).generic_string());
    }
    std::sort(out.begin(), out.end());
    return out;
  }

  /// Writes `text` to dir_ / `name` and returns that path.
  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

  /// The paper design with each `from` replaced by its `to` (first occurrence; each must occur), as dir_ / `name`.
  fs::path design_with(const std::string& name, const std::vector<Edit>& edits) {
    std::string text = slurp(kDesign);
    for (const auto& [from, to] : edits) {
      const auto pos = text.find(from);
      EXPECT_NE(pos, std::string::npos) << from;
      if (pos != std::string::npos) text.replace(pos, from.size(), to);
    }
    return write(name, text);
  }

  /// The paper design with `from` replaced by `to` (first occurrence; it must occur), as dir_ / `name`.
  fs::path design_with(const std::string& name, const std::string& from, const std::string& to) {
    return design_with(name, std::vector<Edit>{{from, to}});
  }

  /// The paper design without the block from `start` up to (not including) `end`, as dir_ / `name`.
  fs::path design_without(const std::string& name, const std::string& start, const std::string& end) {
    std::string text = slurp(kDesign);
    const auto a = text.find(start);
    const auto b = text.find(end, a);
    EXPECT_TRUE(a != std::string::npos && b != std::string::npos) << start;
    if (a != std::string::npos && b != std::string::npos) text.erase(a, b - a);
    return write(name, text);
  }

  ScratchDir scratch_;                    ///< removed with everything in it after the test
  const fs::path dir_ = scratch_.path();  ///< the scratch directory: the binary's working directory
};

}  // namespace fivebar::testing
