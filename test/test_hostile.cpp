// Hostile input against the real `fivebar` binary (README "Hardening"): malformed and malicious
// design files, bad command-line values, bad CSV batch files, unwritable outputs. For every case:
//   - the child ends within a time bound (else it is killed and the case fails);
//   - the exit code is the documented one (2 bad input; 3 output that cannot be written);
//   - stderr names the problem (each expected fragment appears), in a bounded message, with no
//     sanitizer report, no "internal error" and no signed zero ("-0.00");
//   - stdout is empty (unless a batch may stream rows before the bad one);
//   - nothing is created: the scratch directory (the working directory, which also holds the
//     --out and --output targets) lists exactly the inputs before and after.
//
// Adding a case (e.g. for a new subcommand) is adding one entry to cases() below. Paths in
// `args` are relative to the scratch directory; `out` is the conventional output directory.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "process.hpp"

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;
namespace ft = fivebar::testing;

namespace {

// A small valid design; cases change one line of it. Line numbers matter for the messages.
const std::string kGood =
    "name: hostile\n"                                                   // 1
    "stations:\n"                                                       // 2
    "  index:\n"                                                        // 3
    "    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}\n"    // 4
    "    mechanisms:\n"                                                 // 5
    "      lower:\n"                                                    // 6
    "        bases: [[0, 0], [12.5, 0]]\n"                              // 7
    "        links: [9, 9, 15, 15]\n"                                   // 8
    "        working_mode: \"-+\"\n"                                    // 9
    "        assembly_mode: \"+\"\n";                                   // 10

// The upper mechanism, for the subcommands that need both (lines 11-15 when appended).
const std::string kUpper =
    "      upper:\n"
    "        bases: [[0, 31], [12.5, 31]]\n"
    "        links: [9, 9, 15, 15]\n"
    "        working_mode: \"+-\"\n"
    "        assembly_mode: \"-\"\n";

std::string good_with(const std::string& from, const std::string& to) {
  std::string text = kGood;
  const auto pos = text.find(from);
  if (pos == std::string::npos) throw std::logic_error("kGood has no '" + from + "'");
  text.replace(pos, from.size(), to);
  return text;
}

std::string repeat(const std::string& s, std::size_t n) {
  std::string out;
  out.reserve(s.size() * n);
  for (std::size_t i = 0; i < n; ++i) out += s;
  return out;
}

/// Something to create in the scratch directory before the run.
struct Input {
  std::string name;
  std::function<void(const fs::path&)> make;  ///< creates the file or directory at the path
};

Input text(std::string name, std::string content) {
  return {std::move(name), [content](const fs::path& p) {
            std::ofstream f(p, std::ios::binary);
            f.write(content.data(), static_cast<std::streamsize>(content.size()));
          }};
}
Input sparse(std::string name, std::uintmax_t bytes) {
  return {std::move(name), [bytes](const fs::path& p) {
            std::ofstream(p, std::ios::binary) << "name: big\n";
            fs::resize_file(p, bytes);  // a hole: no disk space, no time
          }};
}
Input directory(std::string name) {
  return {std::move(name), [](const fs::path& p) { fs::create_directories(p); }};
}

struct Case {
  std::string name;                   ///< gtest name: letters, digits, _
  std::vector<std::string> args;      ///< after `fivebar`
  std::vector<Input> inputs;          ///< created first, in the scratch directory
  std::vector<std::string> messages;  ///< each must appear on stderr
  int exit_code = 2;
  bool rows_may_stream = false;          ///< a batch without --output may print rows before the bad one
  std::vector<std::string> not_messages;  ///< none of these may appear on stderr
  unsigned long memory_kb = 0;            ///< run under `ulimit -v` of this many KiB (0: no limit)
};

std::ostream& operator<<(std::ostream& os, const Case& c) { return os << c.name; }

const std::vector<std::string> kIndexLower{"--station", "index", "--mechanism", "lower"};

std::vector<std::string> cat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

/// `fivebar run bad.yaml --out out` on a design file with this content.
Case design_case(std::string name, std::string content, std::vector<std::string> messages) {
  return {std::move(name), {"run", "bad.yaml", "--out", "out"}, {text("bad.yaml", std::move(content))},
          std::move(messages)};
}

std::string random_bytes(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::string s(n, '\0');
  for (char& c : s) c = static_cast<char>(rng() & 0xFF);
  return s;
}

std::vector<Case> cases() {
  const std::string L = "stations.index.mechanisms.lower.";
  std::vector<Case> c;

  // --- Malformed YAML -----------------------------------------------------------------------------
  c.push_back(design_case("YamlUnclosedFlowList", "name: x\nstations: [\n", {"bad.yaml:", "YAML syntax error"}));
  c.push_back(design_case("YamlUnclosedQuote", "name: \"x\nstations: {}\n",
                          {"bad.yaml:1:", "quoted string that starts at column 7 is never closed"}));
  c.push_back(design_case("YamlTabIndentation", good_with("    mechanisms:", "\tmechanisms:"),
                          {"bad.yaml:5:", "YAML syntax error"}));
  c.push_back(design_case("YamlBadIndentation", good_with("        links:", "          links:"),
                          {"bad.yaml:", "YAML syntax error"}));
  c.push_back(design_case("YamlTwoDocuments", kGood + "---\n" + kGood, {"bad.yaml:", "one YAML document"}));
  c.push_back(design_case("YamlUndefinedAlias", good_with("name: hostile", "name: *nowhere"),
                          {"bad.yaml:1:", "YAML syntax error", "anchor is not defined"}));
  // yaml-cpp 0.7's LoadAll() loops forever, allocating, on a stray ',' (found by fuzz_design_loader).
  {
    std::string indented;  // the top-level map indented, then a ',' left of it
    for (std::size_t at = 0, end; (end = kGood.find('\n', at)) != std::string::npos; at = end + 1) {
      indented += "  " + kGood.substr(at, end - at + 1);
    }
    c.push_back(design_case("YamlStrayComma", indented + " , 12]}\n", {"bad.yaml:11:", "unexpected ','"}));
  }
  c.push_back(design_case("YamlOnlyAComma", ",", {"bad.yaml:1:", "unexpected ','"}));
  c.push_back(design_case("YamlBinaryGarbage", random_bytes(4096, 42), {"bad.yaml:", "not UTF-8"}));

  // --- Wrong types --------------------------------------------------------------------------------
  c.push_back(design_case("LinksAString", good_with("[9, 9, 15, 15]", "\"9, 9, 15, 15\""),
                          {"bad.yaml:8: " + L + "links", "must be a list of 4"}));
  c.push_back(design_case("LinkAQuotedNumber", good_with("[9, 9, 15, 15]", "[9, 9, \"15\", 15]"),
                          {"bad.yaml:8: " + L + "links[2]", "not a quoted string"}));
  c.push_back(design_case("LinkABoolean", good_with("[9, 9, 15, 15]", "[9, 9, true, 15]"),
                          {"bad.yaml:8: " + L + "links[2] = true", "not a boolean"}));
  c.push_back(design_case("StationsAList", "name: x\nstations: [index, thumb]\n",
                          {"bad.yaml:2: stations", "must be a map"}));
  c.push_back(design_case("NameAMap", good_with("name: hostile", "name: {first: a}"), {"bad.yaml:1: name"}));
  c.push_back(design_case("TopLevelAList", "- name\n- stations\n", {"bad.yaml:1:", "must hold a map"}));

  // --- Huge numbers, NaN and infinity spelled in YAML -----------------------------------------------
  c.push_back(design_case("Link1e308", good_with("[9, 9, 15, 15]", "[9, 9, 1e308, 15]"),
                          {"bad.yaml:8: " + L + "links[2]", "1e+308", "must be <= 1e12"}));
  c.push_back(design_case("Link1e400", good_with("[9, 9, 15, 15]", "[9, 9, 1e400, 15]"),
                          {"bad.yaml:8: " + L + "links[2] = 1e400", "must be a finite number"}));
  c.push_back(design_case("BaseMinus1e400", good_with("[[0, 0], [12.5, 0]]", "[[0, -1e400], [12.5, 0]]"),
                          {"bad.yaml:7: " + L + "bases[0][1] = -1e400", "finite"}));
  c.push_back(design_case("LinkDotNan", good_with("[9, 9, 15, 15]", "[9, .nan, 15, 15]"),
                          {"bad.yaml:8: " + L + "links[1] = .nan", "finite"}));
  c.push_back(design_case("LinkPlainNaN", good_with("[9, 9, 15, 15]", "[9, NaN, 15, 15]"),
                          {"bad.yaml:8: " + L + "links[1] = NaN", "finite"}));
  c.push_back(design_case("LinkDotInf", good_with("[9, 9, 15, 15]", "[9, 9, 15, .inf]"),
                          {"bad.yaml:8: " + L + "links[3] = .inf", "finite"}));
  c.push_back(design_case("AngleMinusDotInf", good_with("angle: 0", "angle: -.Inf"),
                          {"bad.yaml:4: stations.index.target.angle = -.Inf", "finite"}));
  c.push_back(design_case("AxisPlainInfinity", good_with("axes: [15, 12]", "axes: [15, infinity]"),
                          {"bad.yaml:4: stations.index.target.axes[1] = infinity", "finite"}));
  c.push_back(design_case("LinkHexFloat", good_with("[9, 9, 15, 15]", "[9, 9, 0x1p4, 15]"),
                          {"bad.yaml:8: " + L + "links[2] = 0x1p4", "must be a number"}));

  // --- Nesting, size, aliases: refused before or without exhausting the stack or memory ------------
  c.push_back(design_case("NestedFlowLists100k", "name: x\nstations: " + repeat("[", 100000) + "\n",
                          {"bad.yaml:2:", "nested more than 64 levels"}));
  c.push_back(design_case("NestedFlowMaps100k", "name: x\nstations: " + repeat("{a: ", 100000) + "\n",
                          {"bad.yaml:2:", "nested more than 64 levels"}));
  c.push_back(design_case("NestedBlockItems100k", repeat("- ", 100000) + "x\n",
                          {"bad.yaml:1:", "nested more than 64 levels"}));
  {
    std::string deep = "name: x\nstations:\n";
    for (int i = 0; i < 1000; ++i) deep += std::string(static_cast<std::size_t>(i) + 2, ' ') + "k:\n";
    c.push_back(design_case("NestedBlockMaps1000", deep, {"bad.yaml:", "nested more than 64 levels"}));
  }
  {
    // Nine anchors, each a list of ten aliases of the previous one: name expands to 10^9 leaves.
    // yaml-cpp shares aliased nodes; the loader must not expand them either (its messages show
    // at most 60 characters of a value).
    std::string bomb = "products: [&a0 [x, x, x, x, x, x, x, x, x, x]";
    for (int i = 1; i <= 8; ++i) {
      const std::string prev = "*a" + std::to_string(i - 1);
      bomb += ", &a" + std::to_string(i) + " [" + repeat(prev + ", ", 9) + prev + "]";
    }
    bomb += "]\nname: *a8\nstations: {}\n";
    c.push_back(design_case("AliasBomb", bomb, {"bad.yaml:2: name = [[[[[[[[[x, x", "must be a name"}));
  }
  c.push_back({"FileOf50MB", {"run", "big.yaml", "--out", "out"}, {sparse("big.yaml", 50u << 20)},
               {"big.yaml: 52428800 bytes", "at most 1048576 bytes"}});
  c.push_back(design_case("FileJustOverTheLimit", kGood + "# " + repeat("x", (1u << 20) - kGood.size()) + "\n",
                          {"bad.yaml: 1048579 bytes", "at most 1048576 bytes"}));
  c.push_back({"DevZeroAsDesign", {"run", "/dev/zero", "--out", "out"}, {},
               {"/dev/zero: more than 1048576 bytes", "at most"}});
  c.push_back(design_case("ListOf100kLinks", good_with("[9, 9, 15, 15]", "[" + repeat("9, ", 100000) + "9]"),
                          {"bad.yaml:8: " + L + "links", "not 100001 elements"}));
  c.push_back(design_case("KeyOf500Characters", kGood + repeat("k", 500) + ": 1\n",
                          {"bad.yaml:11:", "too long for a key", "(500 bytes)"}));
  c.push_back(design_case("KeyOf10kCharacters", kGood + repeat("k", 10000) + ": 1\n",
                          {"bad.yaml:11:", "YAML syntax error"}));  // yaml-cpp: keys are at most 1024
  c.push_back(design_case("NameOf100kCharacters", good_with("name: hostile", "name: " + repeat("n", 100000)),
                          {"bad.yaml:1: name", "(100000 bytes)", "safe file name"}));

  // --- Keys ---------------------------------------------------------------------------------------
  c.push_back(design_case("UnknownTopLevelKey", kGood + "colour: red\n", {"bad.yaml:11: colour", "unknown key"}));
  c.push_back(design_case("MisspeltMechanismKey", good_with("links:", "lenks:"),
                          {"bad.yaml:8: " + L + "lenks", "unknown key", "did you mean 'links'"}));
  c.push_back(design_case("DuplicateKey", good_with("        links: [9, 9, 15, 15]\n",
                                                    "        links: [9, 9, 15, 15]\n        links: [9, 9, 16, 16]\n"),
                          {"bad.yaml:9: " + L + "links", "duplicate key", "line 8"}));
  c.push_back(design_case("DuplicateStation", kGood + "  index:\n    target: {center: [0, 0], axes: [1, 1]}\n",
                          {"bad.yaml:11: stations.index", "duplicate key"}));
  c.push_back(design_case("NonScalarKey", kGood + "[a, b]: 1\n", {"bad.yaml:11:", "not a name"}));

  // --- Encoding -----------------------------------------------------------------------------------
  c.push_back(design_case("Latin1ByteInName", good_with("name: hostile", "name: caf\xE9"),
                          {"bad.yaml:1:", "byte 0xE9 at column 10", "not UTF-8"}));
  c.push_back(design_case("InvalidUtf8InComment", kGood + "# \xC0\xAF overlong slash\n",
                          {"bad.yaml:11:", "byte 0xC0 at column 3", "not UTF-8"}));
  c.push_back(design_case("Utf16WithBom", std::string("\xFF\xFEn\0a\0m\0e\0", 10), {"bad.yaml:", "UTF-16"}));
  c.push_back(design_case("ControlCharacter", good_with("name: hostile", "name: host\x01ile"),
                          {"bad.yaml:1:", "U+0001 at column 11", "control character"}));
  c.push_back(design_case("NulByte", good_with("name: hostile", std::string("name: host\0ile", 14)),
                          {"bad.yaml:1:", "U+0000", "control character"}));
  c.push_back(design_case("EscapedNulInName", good_with("name: hostile", "name: \"host\\0ile\""),
                          {"bad.yaml:1: name = 'host\\x00ile'", "safe file name"}));

  // --- Empty, missing, not a file -------------------------------------------------------------------
  c.push_back(design_case("EmptyFile", "", {"bad.yaml: empty design file"}));
  c.push_back(design_case("OnlyWhitespace", "\n   \n\n", {"bad.yaml: empty design file"}));
  c.push_back({"DevNullAsDesign", {"run", "/dev/null", "--out", "out"}, {}, {"/dev/null: empty design file"}});
  c.push_back({"DirectoryAsDesign", {"run", "adir", "--out", "out"}, {directory("adir")},
               {"adir: is a directory, not a design file"}});
  c.push_back({"MissingDesign", {"run", "nosuch.yaml", "--out", "out"}, {}, {"nosuch.yaml: no such design file"}});
  c.push_back({"MissingDesignForFk", cat({"fk", "nosuch.yaml"}, cat(kIndexLower, {"--theta", "1,2"})), {},
               {"nosuch.yaml: no such design file"}});

  // --- Names that would leave the output folder -------------------------------------------------
  c.push_back(design_case("NameEscapesUp", good_with("name: hostile", "name: ../../x"),
                          {"bad.yaml:1: name = '../../x'", "safe file name"}));
  c.push_back(design_case("NameAbsolute", good_with("name: hostile", "name: /tmp/x"),
                          {"bad.yaml:1: name = '/tmp/x'", "safe file name"}));
  c.push_back(design_case("NameDotDot", good_with("name: hostile", "name: \"..\""),
                          {"bad.yaml:1: name = '..'", "safe file name"}));
  c.push_back(design_case("StationNameWithSlash", good_with("  index:", "  \"a/../../b\":"),
                          {"bad.yaml:3:", "a/../../b", "safe file name"}));
  c.push_back(design_case("UnknownProductInFile", kGood + "products: [kinematics, nosuch]\n",
                          {"bad.yaml:11: products[1] = 'nosuch'", "unknown product"}));

  // --- Bad command-line values -------------------------------------------------------------------
  const Input good = text("good.yaml", kGood);
  const auto fk = [&](std::vector<std::string> tail) { return cat(cat({"fk", "good.yaml"}, kIndexLower), tail); };
  const auto ik = [&](std::vector<std::string> tail) { return cat(cat({"ik", "good.yaml"}, kIndexLower), tail); };
  c.push_back({"ThetaNotANumber", fk({"--theta", "abc"}), {good}, {"--theta 'abc'", "T1,T2"}});
  c.push_back({"ThetaOneValue", fk({"--theta", "1"}), {good}, {"--theta '1'", "two finite numbers"}});
  c.push_back({"ThetaThreeValues", fk({"--theta", "1,2,3"}), {good}, {"--theta '1,2,3'"}});
  c.push_back({"ThetaNaN", fk({"--theta", "nan,0"}), {good}, {"--theta 'nan,0'", "finite"}});
  c.push_back({"ThetaOverflow", fk({"--theta", "1e400,0"}), {good}, {"--theta '1e400,0'", "finite"}});
  c.push_back({"PointOneValue", ik({"--point", "1"}), {good}, {"--point '1'", "X,Y"}});
  c.push_back({"PointEmptyPair", ik({"--point", ","}), {good}, {"--point ','"}});
  c.push_back({"UnknownStation", {"fk", "good.yaml", "--station", "nosuch", "--theta", "1,2"}, {good},
               {"unknown station 'nosuch'", "index"}});
  c.push_back({"UnknownMechanism", {"fk", "good.yaml", "--station", "index", "--mechanism", "middle", "--theta", "1,2"},
               {good}, {"--mechanism", "middle"}});
  c.push_back({"BadWorkingMode", ik({"--point", "1,2", "--mode", "xx"}), {good}, {"--mode 'xx'"}});
  c.push_back({"UnknownSubcommand", {"frobnicate", "good.yaml"}, {good}, {"unknown subcommand 'frobnicate'", "run"}});
  c.push_back({"UnknownOption", {"run", "good.yaml", "--out", "out", "--frobnicate"}, {good}, {"--frobnicate"}});
  c.push_back({"RunWithoutDesign", {"run", "--out", "out"}, {}, {"DESIGN"}});
  c.push_back({"UnknownProductOption", {"run", "good.yaml", "--out", "out", "--products", "nosuch"}, {good},
               {"unknown product 'nosuch'"}});
  c.push_back({"EmptyOutOption", {"run", "good.yaml", "--out", ""}, {good}, {"--out", "empty"}});

  // --- Outputs that cannot be written: exit 3, nothing half-written ------------------------------
  c.push_back({"OutUnderARegularFile", {"run", "good.yaml", "--out", "blocker/sub"}, {good, text("blocker", "x")},
               {"cannot create directory", "blocker/sub"}, 3});
  c.push_back({"OutIsARegularFile", {"run", "good.yaml", "--out", "blocker"}, {good, text("blocker", "x")},
               {"blocker"}, 3});
  const Input points = text("points.csv", "x_mm,y_mm\n6.25,15.5\n13.75,15.5\n");
  c.push_back({"BatchOutputUnderARegularFile", ik({"--point-file", "points.csv", "--output", "blocker/angles.csv"}),
               {good, points, text("blocker", "x")}, {"cannot write 'blocker/angles.csv'"}, 3});
  c.push_back({"BatchOutputIsADirectory", ik({"--point-file", "points.csv", "--output", "adir"}),
               {good, points, directory("adir")}, {"cannot write 'adir'"}, 3});

  // --- CSV batch files with bad rows --------------------------------------------------------------
  const auto batch = [&](std::string name, std::string csv, std::vector<std::string> messages) {
    return Case{std::move(name), ik({"--point-file", "in.csv", "--output", "angles.csv"}),
                {good, text("in.csv", std::move(csv))}, std::move(messages)};
  };
  c.push_back(batch("CsvRowNotANumber", "x_mm,y_mm\n6.25,15.5\n6.25,abc\n", {"in.csv:3: column 'y_mm' = 'abc'", "finite"}));
  c.push_back(batch("CsvRowNaN", "x_mm,y_mm\n6.25,15.5\nnan,15.5\n", {"in.csv:3: column 'x_mm' = 'nan'", "finite"}));
  c.push_back(batch("CsvRowOverflow", "x_mm,y_mm\n1e999,15.5\n", {"in.csv:2: column 'x_mm' = '1e999'", "finite"}));
  c.push_back(batch("CsvRowTooFewFields", "x_mm,y_mm\n6.25,15.5\n6.25\n", {"in.csv:3:", "1 cells", "the header (line 1) has 2"}));
  c.push_back(batch("CsvMissingColumn", "x,y\n6.25,15.5\n", {"in.csv:1:", "column 'x_mm' is missing"}));
  c.push_back(batch("CsvEmpty", "", {"in.csv:1: empty file", "header"}));
  c.push_back(batch("CsvBinaryRow", "x_mm,y_mm\n6.25,15.5\n\xff\xfe,\x01\n", {"in.csv:3: column 'x_mm' = '"}));
  c.push_back(batch("CsvLineOf2MB", "x_mm,y_mm\n" + repeat("1", 2u << 20) + ",2\n", {"in.csv:2:", "line longer than"}));
  c.push_back({"CsvMissingFile", ik({"--point-file", "nosuch.csv"}), {good}, {"cannot open 'nosuch.csv'"}});
  c.push_back({"CsvIsADirectory", ik({"--point-file", "adir"}), {good, directory("adir")}, {"adir: is a directory"}});
  c.push_back({"CsvFromDevZero", fk({"--theta-file", "/dev/zero"}), {good}, {"/dev/zero:1:", "line longer than"}});
  c.push_back({"ThetaCsvBadRowStreamed", fk({"--theta-file", "in.csv"}),
               {good, text("in.csv", "theta1_deg,theta2_deg\n100,80\n100,eighty\n")},
               {"in.csv:3: column 'theta2_deg' = 'eighty'"}, 2, /*rows_may_stream=*/true});
  c.push_back({"PointAndPointFileTogether", ik({"--point", "1,2", "--point-file", "points.csv"}), {good, points},
               {"--point"}});
  c.push_back({"UnknownNestedSubcommand", {"report", "frobnicate", "good.yaml"}, {good},
               {"unknown subcommand 'frobnicate' of 'report'", "stability"}});

  // --- Other subcommands: absurd sizes and values ----------------------------------------------
  const Input both = text("both.yaml", kGood + kUpper + "geometry:\n");  // default link geometry
  const auto sub = [&](std::vector<std::string> head, std::vector<std::string> tail) {
    return cat(cat(std::move(head), {"both.yaml"}), cat(std::move(tail), {"--out", "out"}));
  };
  c.push_back({"WorkspaceSpacingNotANumber", sub({"workspace"}, {"--spacing", "abc"}), {both}, {"--spacing", "abc"}});
  c.push_back({"WorkspaceSpacingZero", sub({"workspace"}, {"--spacing", "0"}), {both}, {"--spacing = 0 mm", "> 0"}});
  c.push_back({"WorkspaceSpacingNaN", sub({"workspace"}, {"--spacing", "nan"}), {both}, {"--spacing = nan", "finite"}});
  c.push_back({"WorkspaceSpacingTooFine", sub({"workspace"}, {"--spacing", "1e-9"}), {both},
               {"spacing 1e-09 mm needs about ", "e+21 samples", "at most 4000000"}, 2, false,
               {"needs about -"}});
  c.push_back({"WorkspaceSpacingHuge", sub({"workspace"}, {"--spacing", "1e300"}), {both},
               {"spacing 1e+300 mm is larger than the"}, 2, false, {"cairo"}});
  c.push_back({"CoverageEllipseThreeNumbers", {"coverage", "both.yaml", "--ellipse", "1,2,3"}, {both},
               {"--ellipse '1,2,3'", "need 5"}});
  c.push_back({"CoverageEllipseNaN", {"coverage", "both.yaml", "--ellipse", "1,2,3,4,nan"}, {both},
               {"--ellipse '1,2,3,4,nan'", "finite"}});
  c.push_back({"CoverageEllipseNegativeAxis", {"coverage", "both.yaml", "--ellipse", "1,2,-3,4,0"}, {both},
               {"axis lengths must be > 0"}});
  c.push_back({"CollisionPointNotANumber", sub({"collision"}, {"-s", "index", "--upper", "abc", "--lower", "1,2"}),
               {both}, {"--upper 'abc'"}});
  c.push_back({"CollisionSpacingTooFine", sub({"collision"}, {"-s", "index", "--spacing", "1e-9"}), {both},
               {"too fine"}});
  c.push_back({"PatternUnknownKind", sub({"pattern"}, {"-s", "index", "--pattern", "wiggle"}), {both},
               {"--pattern 'wiggle'", "stretch"}});
  c.push_back({"PatternDurationOfYears", sub({"pattern"}, {"-s", "index", "--pattern", "stretch", "--duration", "1e9"}),
               {both}, {"duration_s = 1000000000 s", "<= 3600"}});
  c.push_back({"PatternRateHuge", sub({"pattern"}, {"-s", "index", "--pattern", "stretch", "--rate", "1e9"}), {both},
               {"rate_hz = 1000000000 Hz"}});
  c.push_back({"PatternAmplitudeNaN", sub({"pattern"}, {"-s", "index", "--pattern", "stretch", "--amplitude", "nan"}),
               {both}, {"amplitude_mm = nan"}});
  c.push_back({"AnimateUnknownKind", {"animate", "both.yaml", "-s", "index", "--pattern", "wiggle", "--out", "out"},
               {both}, {"--pattern 'wiggle'", "stretch"}});
  c.push_back({"AnimateGif", {"animate", "both.yaml", "-s", "index", "--pattern", "stretch", "--out", "out/a.gif"}, {both},
               {"SVG only"}});
  c.push_back({"AnimateWithoutPatterns", {"animate", "both.yaml", "-s", "index", "--pattern", "stretch", "--out", "out"},
               {both}, {"no patterns: section"}});
  c.push_back({"AnimateWidthHuge", {"animate", "both.yaml", "-s", "index", "--pattern", "stretch", "--out", "out",
                                    "--width", "1e300"}, {both}, {"--width"}});
  c.push_back({"ControlGridHuge", sub({"control"}, {"--grid", "1000000"}), {both}, {"--grid must be within [3, 401]"}});
  c.push_back({"ControlFieldNotANumber", sub({"control"}, {"--field", "abc"}), {both}, {"--field", "abc"}});
  c.push_back({"ControlTuneSecondsNegative", sub({"control"}, {"--tune", "--tune-seconds", "-1"}), {both},
               {"--tune-seconds must be > 0"}});
  c.push_back({"ControlTuneEvaluationsZero", sub({"control"}, {"--tune", "--per-joint", "--tune-evaluations", "0"}), {both},
               {"--tune-evaluations must be within [1, 10000]"}});
  c.push_back({"ControlWithoutMotorSection", sub({"control"}, {}), {both}, {"both.yaml", "no `motor:` section"}});
  c.push_back({"PartsNoJobs", sub({"parts"}, {"--jobs", "0"}), {both}, {"--jobs", "0"}});
  c.push_back({"SweepBillionSteps", sub({"sweep"}, {"-s", "index", "--vary", "L1=1:2:1000000000"}), {both},
               {"--vary 'L1=1:2:1000000000'"}});
  c.push_back({"SweepVaryNotANumber", sub({"sweep"}, {"-s", "index", "--vary", "L1=abc"}), {both},
               {"--vary 'L1=abc'", "NAME=LO:HI:N"}});
  c.push_back({"SweepShardOutOfRange", sub({"sweep"}, {"-s", "index", "--vary", "L1=8:10:3", "--shard", "5/2"}), {both},
               {"--shard = '5/2'"}});
  c.push_back({"OptimizeWithoutSection", sub({"optimize"}, {"--evaluations", "64"}), {both}, {"no optimize: section"}});
  c.push_back({"OptimizeShardAndMerge", sub({"optimize"}, {"--shard", "0/2", "--merge", "2"}), {both}, {"no optimize: section"}});
  c.push_back({"SweepRandomWithoutCount", sub({"sweep"}, {"-s", "index", "--vary", "L1=8:10:3", "--sample", "random"}), {both},
               {"sweep.count", "required for random sampling"}});
  // --- docs/reliability.md: budgets, key paths, validation before writing, identity, schemas --------------
  // The showcase design (every section), changed by one edit.
  const std::string show = ft::slurp(fs::path(FIVEBAR_SOURCE_DIR) / "designs/iros2022.yaml");
  const auto show_with = [&](const std::string& from, const std::string& to) {
    std::string t = show;
    const auto at = t.find(from);
    if (at == std::string::npos) throw std::logic_error("the showcase has no '" + from + "'");
    t.replace(at, from.size(), to);
    return t;
  };
  const Input showcase = text("show.yaml", show);
  // Family 1: two spellings of one number are one key; 1,200 spellings are refused at once.
  {
    const std::string opt = "optimize:\n  variables:\n    a: {key: \"" + L + "links[2]\", range: [12, 18]}\n";
    c.push_back(design_case("OptimizeOneNumberSpelledTwice",
                            kGood + opt + "    b: {key: \"stations['index'].mechanisms.lower.links[02]\", range: [12, 18]}\n"
                                          "  objectives: [margin]\n",
                            {"bad.yaml:", "optimize.variables.b.key", "already set by optimize.variables.a.key"}));
    std::string keys;
    for (int k = 0; k < 1200; ++k) keys += std::string(k ? ", " : "") + "\"" + L + "links[" + std::string(std::size_t(k), '0') + "2]\"";
    c.push_back(design_case("OptimizeTwelveHundredSpellingsOfOneKey",
                            kGood + "optimize:\n  variables:\n    a: {keys: [" + keys + "], range: [12, 18]}\n  objectives: [margin]\n",
                            {"bad.yaml:", "optimize.variables.a.keys[1]", "already set by optimize.variables.a.keys[0]"}));
  }
  // Family 2: budgets estimated before anything starts, refused beyond the bounds without --yes.
  c.push_back({"ToleranceSamplesHundredMillion", {"tolerance", "t.yaml", "--out", "out"},
               {text("t.yaml", kGood + kUpper + "tolerance: {samples: 100000000}\n")},
               {"tolerance.samples = 100000000", "is large", "GB of memory", "--yes"}});
  c.push_back({"SimulateDenseOverATenMinutePattern",
               {"simulate", "show.yaml", "-s", "index", "--pattern", "stretch", "--dense", "1e-5", "--no-render", "--out", "out"},
               {text("show.yaml", show_with("    duration_s: 1\n    separation_mm: 8            # vertical",
                                            "    duration_s: 600\n    separation_mm: 8            # vertical"))},
               {"dense output", "is large", "GB of files", "--yes"}});
  c.push_back({"AnimateSimulatedDevZero",
               {"animate", "show.yaml", "-s", "index", "--pattern", "stretch", "--out", "out", "--simulated", "/dev/zero"},
               {showcase}, {"/dev/zero:1:", "line longer than 4096 bytes"}});
  // Family 3: bad input refused before the first byte is written; numeric flags are numbers.
  c.push_back({"AnimateSimulatedCoordinateOf1e300",
               {"animate", "show.yaml", "-s", "index", "--pattern", "stretch", "--out", "out", "--simulated", "sim.csv"},
               {showcase, text("sim.csv", "t_s,mechanism,x_mm,y_mm\n0,lower,6.25,15.5\n0.01,lower,1e300,15.5\n")},
               {"sim.csv:3:", "x_mm = 1e+300 mm", "within [-1e12, 1e12]"}});
  c.push_back({"ControlTuneWithoutATwoMechanismStation", {"control", "solo.yaml", "-s", "solo", "--tune", "--out", "out"},
               {text("solo.yaml", show_with("stations:\n", "stations:\n  solo:\n"
                                                            "    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}\n"
                                                            "    mechanisms:\n      lower: {bases: [[0, 0], [12.5, 0]], "
                                                            "links: [9, 9, 15, 15], working_mode: \"-+\", assembly_mode: \"+\"}\n"))},
               {"--tune: no station with both mechanisms"}});
  c.push_back({"OptimizeSecondsNaN", {"optimize", "show.yaml", "--seconds", "nan", "--out", "out"}, {showcase},
               {"--seconds: 'nan'", "finite"}});
  c.push_back({"OptimizeSecondsInfinite", {"optimize", "show.yaml", "--seconds", "inf", "--out", "out"}, {showcase},
               {"--seconds: 'inf'", "finite"}});
  c.push_back({"OptimizeSeedNegative", {"optimize", "show.yaml", "--seed=-1", "--out", "out"}, {showcase},
               {"--seed: '-1'", "whole number >= 0"}});
  c.push_back({"OptimizeEvaluationsOverflow", {"optimize", "show.yaml", "--evaluations", "99999999999999999999999", "--out", "out"},
               {showcase}, {"--evaluations: '99999999999999999999999'", "too large"}});
  c.push_back({"OptimizeSeedFraction", {"optimize", "show.yaml", "--seed", "1.5", "--out", "out"}, {showcase},
               {"--seed: '1.5'", "whole number"}});
  c.push_back({"WorkspaceSpacingOverflow", sub({"workspace"}, {"--spacing", "1e999"}), {both},
               {"--spacing = inf", "finite"}});
  c.push_back({"OptimizeResumeWithoutCheckpoint", {"optimize", "show.yaml", "--resume", "--out", "out"}, {showcase},
               {"checkpoint.json: no checkpoint to resume from"}});
  c.push_back({"ExportCheckNumberBeyondADouble", {"export", "--check", "f.json", "show.yaml"},
               {showcase, text("f.json", "{\"fivebar_controller\": {\"ros__parameters\": {\"x\": 1e999}}}\n")},
               {"f.json", "not a file fivebar exports"}});
  // --- Issue 45: the bench files (docs/bench-files.md): one bounded reader, ranged cells, flags -------
  const std::string meas_header = "station,mechanism,volts1,volts2,x_mm,y_mm\n";
  const std::string meas_row = "index,lower,2.138656037954923,2.861343962045077,6.5124,19.9215\n";
  c.push_back({"CalibrateDevZero", {"calibrate", "show.yaml", "/dev/zero"}, {showcase}, {"/dev/zero", "larger than 67108864 bytes"}});
  c.push_back({"CalibrateYOf1e13", {"calibrate", "show.yaml", "m.csv"},
               {showcase, text("m.csv", meas_header + meas_row + "index,lower,2.1,2.8,6.5,1e13\n")},
               {"m.csv:3: column 'y_mm' = '1e13': outside"}});
  c.push_back({"CalibrateYOf1e308", {"calibrate", "show.yaml", "m.csv"},
               {showcase, text("m.csv", meas_header + meas_row + "index,lower,2.1,2.8,6.5,1e308\n")},
               {"m.csv:3: column 'y_mm' = '1e308': outside"}, 2, false, {"inf", "nan"}});
  c.push_back({"CalibrateVoltsOutsideTheConverter", {"calibrate", "show.yaml", "m.csv"},
               {showcase, text("m.csv", meas_header + meas_row + "index,lower,50,2.8,6.5,19.9\n")},
               {"m.csv:3: column 'volts1' = '50': outside controller.adc.range_v"}});
  c.push_back({"CalibrateCountsInHexadecimal", {"calibrate", "show.yaml", "m.csv"},
               {showcase, text("m.csv", "station,mechanism,counts1,counts2,x_mm,y_mm\nindex,lower,0x10,40000,6.5,19.9\n")},
               {"m.csv:2: column 'counts1' = '0x10': not a finite decimal number"}});
  c.push_back({"CalibrateDuplicatedColumn", {"calibrate", "show.yaml", "m.csv"},
               {showcase, text("m.csv", "station,mechanism,volts1,volts2,x_mm,y_mm,x_mm\n")},
               {"m.csv:1: column 7 'x_mm': duplicate of column 5"}});
  {
    std::string copies = meas_header;
    for (int k = 0; k < 12; ++k) copies += meas_row;
    c.push_back({"CalibrateTwelveCopiesOfOneRow", {"calibrate", "show.yaml", "m.csv"}, {showcase, text("m.csv", copies)},
                 {"m.csv:3: a copy of line 2"}});
  }
  c.push_back({"CalibrateSigmaInfinite", {"calibrate", "show.yaml", "m.csv", "--sigma", "inf"},
               {showcase, text("m.csv", meas_header + meas_row)}, {"--sigma", "inf", "finite"}});
  c.push_back({"CalibratePlanSigmaZero", {"calibrate", "show.yaml", "-s", "index", "--plan", "6", "--plan-sigma", "0", "--out", "out"},
               {showcase}, {"--plan-sigma = 0"}});
  c.push_back({"HardStopOf99Volts", {"calibrate", "show.yaml", "--hard-stops", "h.csv"},
               {showcase, text("h.csv", "station,mechanism,joint,stop,volts\nindex,lower,1,lo,99\n")},
               {"h.csv:2: column 'volts' = '99': outside controller.adc.range_v"}});
  // Bench paths stay beside the design; a refused file is neither read nor echoed.
  c.push_back({"RunBenchCalibrationAbsolute", {"run", "b.yaml", "--out", "out"},
               {text("b.yaml", show_with("calibration: bench/calibration.csv", "calibration: /etc/passwd"))},
               {"b.yaml:", "bench.calibration = /etc/passwd: must be a path relative"}, 2, false, {"root"}});
  c.push_back({"RunBenchReplayLogDotDot", {"run", "b.yaml", "--out", "out"},
               {text("b.yaml", show_with("replay_logs: [bench/replay.csv]", "replay_logs: [bench/../../r.csv]"))},
               {"b.yaml:", "bench.replay_logs[0] = bench/../../r.csv: must not leave"}});
  c.push_back({"RunBenchCalibrationLinkLeadingOut", {"run", "b.yaml", "--out", "out"},
               {text("b.yaml", show_with("calibration: bench/calibration.csv", "calibration: cal.csv")),
                {"cal.csv", [](const fs::path& p) { fs::create_symlink("/etc/passwd", p); }}},
               {"bench.calibration = cal.csv: a symbolic link that leads out"}, 2, false, {"root", "passwd"}});
  // A bad bench file leaves no empty output folder behind.
  c.push_back({"RunBenchCalibrationMalformed", {"run", "b.yaml", "--out", "out"},
               {text("b.yaml", show_with("calibration: bench/calibration.csv", "calibration: cal.csv")),
                text("cal.csv", meas_header + "index,lower,2.1,2.8,6.5,junk\n")},
               {"cal.csv:2: column 'y_mm' = 'junk'"}});
  // --- Issue 45: the last readers through the one bounded reader (docs/reliability.md) ----------------
  const std::vector<std::string> animate_sim{"animate", "show.yaml", "-s", "index", "--pattern", "stretch", "--out", "out",
                                             "--simulated", "sim.csv"};
  c.push_back({"AnimateSimulatedHexadecimalCell", animate_sim,
               {showcase, text("sim.csv", "t_s,mechanism,x_mm,y_mm\n0,lower,6.25,15.5\n0.01,lower,0x10,15.5\n")},
               {"sim.csv:3: column 'x_mm' = '0x10': not a finite decimal number"}});
  c.push_back({"AnimateSimulatedDuplicatedColumn", animate_sim,
               {showcase, text("sim.csv", "t_s,mechanism,x_mm,y_mm,x_mm\n0,lower,6.25,15.5,1e300\n")},
               {"sim.csv:1: column 5 'x_mm': duplicate of column 3"}});
  c.push_back({"AnimateSimulatedUnknownMechanism", animate_sim,
               {showcase, text("sim.csv", "t_s,mechanism,x_mm,y_mm\n0,lower,6.25,15.5\n0,middle,6.25,15.5\n")},
               {"sim.csv:3: column 'mechanism' = 'middle': not lower or upper"}});
  c.push_back({"BatchDuplicatedColumn", ik({"--point-file", "in.csv", "--output", "angles.csv"}),
               {good, text("in.csv", "x_mm,y_mm,x_mm\n6.25,15.5,13.75\n")}, {"in.csv:1: column 3 'x_mm': duplicate of column 1"}});
  c.push_back({"BatchLineOf5000Bytes", ik({"--point-file", "in.csv", "--output", "angles.csv"}),
               {good, text("in.csv", "x_mm,y_mm\n6.25," + std::string(5000, ' ') + "15.5\n")},
               {"in.csv:2: line longer than 4096 bytes"}});
  // 2 GiB of zeros (a hole) read whole under a 1 GB address space: bad_alloc before.
  c.push_back({"ExportCheckTwoGigabytes", {"export", "--check", "big.json", "show.yaml"}, {showcase, sparse("big.json", 2ull << 30)},
               {"big.json", "larger than 67108864 bytes"}, 2, false, {}, 1000000});
  {
    // A typo in a column's station is named where it is (before: "no columns for joint index_lower_theta1").
    std::string log = ft::slurp(fs::path(FIVEBAR_SOURCE_DIR) / "designs/bench/replay.csv");
    for (std::size_t at; (at = log.find("index_lower_theta1_")) != std::string::npos;) log.replace(at, 18, "indx_lower_theta1");
    c.push_back({"IdentifyColumnOfAnUnknownStation",
                 {"identify", "show.yaml", "log.csv", "--rig", "mechanism", "index/lower", "--no-files", "--no-output-error"},
                 {showcase, text("log.csv", log)}, {"log.csv:2: column 2 'indx_lower_theta1_...': the design has no station 'indx'"}});
  }
  c.push_back({"IdentifyCutoffZero", {"identify", "show.yaml", "id.csv", "--cutoff", "0", "--out", "out"},
               {showcase, text("id.csv", ft::slurp(fs::path(FIVEBAR_SOURCE_DIR) / "designs/bench/identification.csv"))},
               {"--cutoff = 0"}});
  c.push_back({"IdentifyDecimationZero", {"identify", "show.yaml", "id.csv", "--decimation", "0", "--out", "out"},
               {showcase, text("id.csv", ft::slurp(fs::path(FIVEBAR_SOURCE_DIR) / "designs/bench/identification.csv"))},
               {"--decimation = 0"}});
  return c;
}

class Hostile : public ::testing::TestWithParam<Case> {};

TEST_P(Hostile, RefusedCleanlyAndNothingWritten) {
  const Case& k = GetParam();
  ft::ScratchDir io("fivebar_hostile_io");
  ft::ScratchDir scratch("fivebar_hostile");
  for (const Input& in : k.inputs) in.make(scratch.path() / in.name);
  const auto before = ft::tree(scratch.path());

  const double bound = ft::child_timeout_s(10.0);
  // A memory limit: through the shell's ulimit, which the binary inherits (exec).
  std::vector<std::string> args = k.args;
  std::string program = FIVEBAR_BINARY;
#ifndef FIVEBAR_SANITIZE
  // (Not in the sanitizer build: AddressSanitizer reserves terabytes of address space for its
  // shadow, so a sanitized process cannot start under `ulimit -v`; the Release suite checks the bound.)
  if (k.memory_kb > 0) {
    args.insert(args.begin(), {"-c", "ulimit -v " + std::to_string(k.memory_kb) + " && exec \"$0\" \"$@\"", FIVEBAR_BINARY});
    program = "/bin/sh";
  }
#endif
  const ft::Outcome r = ft::run(program, args, scratch.path(), io.path(), bound);
  ASSERT_TRUE(r.spawned);
  std::string command = "fivebar";
  for (const auto& a : k.args) command += " " + (a.size() > 60 ? a.substr(0, 60) + "..." : a);
  SCOPED_TRACE(command + "\nstderr: " + r.err.substr(0, 2000));

  EXPECT_FALSE(r.timed_out) << "still running after " << bound << " s (killed)";
  EXPECT_EQ(r.signal, 0) << "killed by signal " << r.signal;
  EXPECT_EQ(r.code, k.exit_code);
  for (const auto& m : k.messages) EXPECT_THAT(r.err, HasSubstr(m));
  for (const auto& m : k.not_messages) EXPECT_THAT(r.err, Not(HasSubstr(m)));
  EXPECT_FALSE(r.err.empty());
  EXPECT_LT(r.err.size(), 2000u) << "the message should name the problem, not dump the input";
  EXPECT_THAT(r.err, Not(HasSubstr("internal error")));
  EXPECT_THAT(r.err, Not(HasSubstr("Sanitizer")));
  EXPECT_THAT(r.err, Not(HasSubstr("runtime error:")));
  // Every number in a message goes through fivebar/format.hpp: none reads as a signed zero.
  EXPECT_THAT(r.err, Not(::testing::ContainsRegex("-0\\.0+([^0-9]|$)"))) << "a signed zero in the message";
  if (!k.rows_may_stream) EXPECT_EQ(r.out, "");
  EXPECT_EQ(ft::tree(scratch.path()), before) << "files were created, changed or removed";
}

INSTANTIATE_TEST_SUITE_P(Cases, Hostile, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<Case>& info) { return info.param.name; });

TEST(HostileSuite, HasAtLeastFortyDistinctCases) {
  const auto all = cases();
  EXPECT_GE(all.size(), 40u);
  std::set<std::string> names;
  for (const auto& k : all) EXPECT_TRUE(names.insert(k.name).second) << "duplicate case " << k.name;
}

/// The harness itself: the same good design runs cleanly and writes where it is told, so the
/// "nothing written" checks above are not vacuous.
TEST(HostileSuite, GoodDesignRunsAndWritesOnlyUnderOut) {
  ft::ScratchDir io("fivebar_hostile_io");
  ft::ScratchDir scratch("fivebar_hostile");
  text("good.yaml", kGood).make(scratch.path() / "good.yaml");
  const ft::Outcome r =
      ft::run(FIVEBAR_BINARY, {"run", "good.yaml", "--out", "out", "--quiet"}, scratch.path(), io.path(), ft::child_timeout_s());
  EXPECT_EQ(r.code, 0) << r.err;
  const auto files = ft::tree(scratch.path());
  ASSERT_GE(files.size(), 5u);
  EXPECT_EQ(files[0].substr(0, 10), "good.yaml ");
  EXPECT_EQ(files[1], "out/");
  EXPECT_EQ(files[2], "out/hostile/");
  for (std::size_t i = 3; i < files.size(); ++i) {
    EXPECT_EQ(files[i].rfind("out/hostile/", 0), 0u) << files[i];
    EXPECT_EQ(files[i].find(".tmp."), std::string::npos) << files[i];
  }
}

}  // namespace
