// Output hygiene (README "Hardening"; docs/reliability.md "Output files"):
//   - every writer in lib/ and cli/ goes through fivebar/io.hpp (a source scan);
//   - a signal removes the temporaries of unfinished files and still ends the process;
//   - WriteFence confines writes, and `fivebar run` fences its --out;
//   - SIGINT / SIGTERM sent to a running `fivebar run` at many moments leave only complete files.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "process.hpp"

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ::testing::HasSubstr;

namespace {

const fs::path kSource = FIVEBAR_SOURCE_DIR;

// --- Every writer goes through io.hpp ------------------------------------------------------------

/// Calls that create, replace or write files by name. Outside lib/src/io.cpp they would bypass the
/// temporary-and-rename discipline, the signal clean-up and the write fence. A line that really
/// needs one (reading with std::fstream, say) carries the comment `hygiene: allowed (why)`.
const std::vector<std::pair<std::string, std::regex>>& forbidden() {
  static const std::vector<std::pair<std::string, std::regex>> list = {
      {"std::ofstream / std::fstream", std::regex(R"(\b(std::)?(w?ofstream|w?fstream)\b)")},
      {"fopen / freopen", std::regex(R"(\b(fopen|freopen|fdopen)\s*\()")},
      {"open(... O_CREAT / O_WRONLY / O_RDWR)", std::regex(R"(\bO_(CREAT|WRONLY|RDWR|TRUNC)\b)")},
      {"rename / link / creat", std::regex(R"((\b|::)(rename|renameat|link|creat)\s*\()")},
      {"std::filesystem copy / rename", std::regex(R"(\b(fs|filesystem)::(copy|copy_file|rename|create_symlink)\b)")},
      {"cairo writing a file by name", std::regex(R"(\bcairo_(svg|pdf|ps)_surface_create\s*\(|\bcairo_surface_write_to_png\s*\()")},
      {"VTK writer with a file name", std::regex(R"(\bSetFileName\s*\()")},
  };
  return list;
}

TEST(OutputHygiene, EveryWriterGoesThroughIoHpp) {
  std::vector<std::string> offences;
  std::size_t scanned = 0;
  for (const char* top : {"lib", "cli"}) {
    for (const auto& e : fs::recursive_directory_iterator(kSource / top)) {
      const fs::path& p = e.path();
      if (!e.is_regular_file() || (p.extension() != ".cpp" && p.extension() != ".hpp")) continue;
      if (p == kSource / "lib" / "src" / "io.cpp") continue;  // the one place that writes
      ++scanned;
      std::ifstream in(p);
      std::string line;
      for (int n = 1; std::getline(in, line); ++n) {
        if (line.find("hygiene: allowed") != std::string::npos) continue;
        if (line.starts_with("#include")) continue;
        std::string code = line.substr(0, line.find("//"));
        for (const auto& [what, re] : forbidden()) {
          if (std::regex_search(code, re)) {
            offences.push_back(fs::relative(p, kSource).string() + ":" + std::to_string(n) + ": " + what + ": " + line);
          }
        }
      }
    }
  }
  EXPECT_GT(scanned, 10u);
  EXPECT_THAT(offences, ::testing::IsEmpty()) << "write through fivebar/io.hpp (write_file_atomic, AtomicFile)";
}

TEST(OutputHygiene, TheScanRecognisesEachForbiddenCall) {
  const std::vector<std::string> samples = {
      "std::ofstream out(path);",          "FILE* f = fopen(name, \"w\");",
      "int fd = ::open(p, O_WRONLY);",     "std::rename(a, b);",
      "fs::copy_file(a, b);",              "cairo_svg_surface_create(name, w, h);",
      "cairo_surface_write_to_png(s, n);", "writer->SetFileName(name.c_str());",
  };
  for (const auto& s : samples) {
    bool hit = false;
    for (const auto& [what, re] : forbidden()) hit = hit || std::regex_search(s, re);
    EXPECT_TRUE(hit) << s;
  }
  for (const std::string ok : {"std::ifstream in(path);", "cairo_svg_surface_create_for_stream(write, &out, w, h);",
                               "write_file_atomic(path, text);", "AtomicFile f(path);"}) {
    bool hit = false;
    for (const auto& [what, re] : forbidden()) hit = hit || std::regex_search(ok, re);
    EXPECT_FALSE(hit) << ok;
  }
}

// --- Signals remove unfinished temporaries ----------------------------------------------------------

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

/// In a forked child: one committed file, one unfinished AtomicFile, then `sig` raised.
/// Returns the child's wait status.
int child_interrupted_while_writing(const fs::path& dir, int sig, bool ignore_first) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (ignore_first) ::signal(sig, SIG_IGN);
    fivebar::install_interrupt_cleanup();
    fivebar::write_file_atomic(dir / "done.txt", "complete\n");
    fivebar::AtomicFile open(dir / "half.txt");
    open.stream() << "half of it";
    open.stream().flush();
    if (!fs::exists(open.temp_path())) ::_exit(90);
    ::raise(sig);
    ::_exit(91);  // reached only when the signal is ignored; the destructor is skipped on purpose
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

class InterruptCleanup : public ::testing::TestWithParam<int> {};

TEST_P(InterruptCleanup, RemovesTheTemporaryAndEndsBySignal) {
  const int sig = GetParam();
  ft::ScratchDir dir("fivebar_interrupt");
  const int status = child_interrupted_while_writing(dir.path(), sig, false);
  ASSERT_TRUE(WIFSIGNALED(status)) << "exit " << (WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  EXPECT_EQ(WTERMSIG(status), sig);
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"done.txt"});
  EXPECT_EQ(ft::slurp(dir.path() / "done.txt"), "complete\n");
}

TEST_P(InterruptCleanup, AnIgnoredSignalStaysIgnored) {
  const int sig = GetParam();
  ft::ScratchDir dir("fivebar_interrupt");
  const int status = child_interrupted_while_writing(dir.path(), sig, true);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 91);  // carried on past raise()
  EXPECT_EQ(names_in(dir.path()).size(), 2u);  // done.txt and the temporary, left by _exit
}

INSTANTIATE_TEST_SUITE_P(Signals, InterruptCleanup, ::testing::Values(SIGINT, SIGTERM, SIGHUP, SIGPIPE),
                         [](const ::testing::TestParamInfo<int>& i) { return std::string(sigabbrev_np(i.param)); });

TEST(InterruptCleanupTable, ManyOpenFilesAreAllRemoved) {
  ft::ScratchDir dir("fivebar_interrupt");
  const pid_t pid = ::fork();
  if (pid == 0) {
    fivebar::install_interrupt_cleanup();
    std::vector<fivebar::AtomicFile> files;
    for (int i = 0; i < 300; ++i) files.emplace_back(dir.path() / ("f" + std::to_string(i)));  // more than the table
    for (int i = 0; i < 250; ++i) files.pop_back();  // destructors remove these normally
    ::raise(SIGTERM);
    ::_exit(91);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{});
}

// --- Write fences -----------------------------------------------------------------------------------

TEST(WriteFence, RefusesWritesOutsideAndAllowsInside) {
  ft::ScratchDir dir("fivebar_fence");
  const fs::path inside = dir.path() / "out";
  fs::create_directories(inside);
  {
    const fivebar::WriteFence fence(inside);
    EXPECT_NO_THROW(fivebar::write_file_atomic(inside / "a.txt", "a"));
    EXPECT_NO_THROW(fivebar::make_directories(inside / "x" / "y"));
    EXPECT_NO_THROW(fivebar::make_directories(inside));
    EXPECT_THAT([&] { fivebar::write_file_atomic(dir.path() / "b.txt", "b"); },
                ::testing::ThrowsMessage<fivebar::IoError>(HasSubstr("outside the output directory")));
    EXPECT_THROW(fivebar::write_file_atomic(inside / ".." / "c.txt", "c"), fivebar::IoError);
    EXPECT_THROW(fivebar::make_directories(dir.path() / "sibling"), fivebar::IoError);
    EXPECT_THROW(fivebar::AtomicFile(dir.path() / "out2" / "d.txt"), fivebar::IoError);  // a prefix is not inside
    {
      const fivebar::WriteFence inner(inside / "x");
      EXPECT_NO_THROW(fivebar::write_file_atomic(inside / "x" / "e.txt", "e"));
      EXPECT_THROW(fivebar::write_file_atomic(inside / "f.txt", "f"), fivebar::IoError);  // both fences apply
    }
    EXPECT_NO_THROW(fivebar::write_file_atomic(inside / "f.txt", "f"));
  }
  EXPECT_NO_THROW(fivebar::write_file_atomic(dir.path() / "g.txt", "g"));  // fence gone
  EXPECT_FALSE(fs::exists(dir.path() / "b.txt"));
  EXPECT_FALSE(fs::exists(dir.path() / "c.txt"));
  EXPECT_FALSE(fs::exists(dir.path() / "sibling"));
  EXPECT_FALSE(fs::exists(dir.path() / "out2"));
}

TEST(WriteFence, RelativeFenceAndTargetAreComparedFromTheWorkingDirectory) {
  ft::ScratchDir dir("fivebar_fence");
  const fs::path saved = fs::current_path();
  fs::current_path(dir.path());
  {
    const fivebar::WriteFence fence("out/");
    EXPECT_NO_THROW(fivebar::make_directories("out/a"));
    EXPECT_NO_THROW(fivebar::write_file_atomic(dir.path() / "out" / "a" / "x.txt", "x"));  // absolute, inside
    EXPECT_THROW(fivebar::write_file_atomic("x.txt", "x"), fivebar::IoError);
    EXPECT_THROW(fivebar::write_file_atomic("out/a/../../x.txt", "x"), fivebar::IoError);
  }
  fs::current_path(saved);
  EXPECT_TRUE(fs::exists(dir.path() / "out" / "a" / "x.txt"));
  EXPECT_FALSE(fs::exists(dir.path() / "x.txt"));
}

// --- Interrupting a real `fivebar run` -----------------------------------------------------------

/// A scene big enough that `run` takes a while: many copies of the index station.
std::string stress_scene(int stations) {
  std::string s = "name: stress\nproducts: [kinematics]\nstations:\n";
  for (int i = 0; i < stations; ++i) {
    s += "  s" + std::to_string(i) +
         ":\n"
         "    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}\n"
         "    mechanisms:\n"
         "      lower: {bases: [[0, 0], [12.5, 0]], links: [9, 9, 15, 15], working_mode: \"-+\", assembly_mode: \"+\"}\n"
         "      upper: {bases: [[0, 31], [12.5, 31]], links: [9, 9, 15, 15], working_mode: \"+-\", assembly_mode: \"-\"}\n";
  }
  return s;
}

/// The summaries with each product's wall time masked (summary.json "wall_s", the "time (s)" cell
/// of summary.md and of index.html's table): the only bytes two complete runs may differ in.
std::string without_wall_times(const std::string& text) {
  static const std::regex json_time("\"wall_s\": [-+0-9.eE]+");
  static const std::regex html_time("<td class=\"r\">[0-9.]+</td>");
  static const std::regex md_time("^(\\| [^|]+\\| [^|]+\\| [^|]+\\| )[0-9.]+( \\|)");
  std::string out = std::regex_replace(text, json_time, "\"wall_s\": T");
  out = std::regex_replace(out, html_time, "<td class=\"r\">T</td>");
  std::istringstream lines(out);
  std::string masked, line;
  while (std::getline(lines, line)) masked += std::regex_replace(line, md_time, "$1T$2") + "\n";
  return masked;
}

std::map<std::string, std::string> files_under(const fs::path& root) {
  std::map<std::string, std::string> out;
  if (!fs::exists(root)) return out;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file()) out[fs::relative(e.path(), root).generic_string()] = without_wall_times(ft::slurp(e.path()));
  }
  return out;
}

TEST(InterruptedRun, LeavesOnlyCompleteFilesWheneverTheSignalLands) {
  ft::ScratchDir io("fivebar_interrupt_io");
  ft::ScratchDir reference_dir("fivebar_interrupt_ref");
  const std::string scene = stress_scene(400);
  std::ofstream(reference_dir.path() / "scene.yaml") << scene;
  const std::vector<std::string> args{"run", "scene.yaml", "--out", "out", "--quiet"};

  // The uninterrupted run: what every file must be, byte for byte but for the products' wall
  // times, if it exists at all.
  const ft::Outcome full = ft::run(FIVEBAR_BINARY, args, reference_dir.path(), io.path(), ft::child_timeout_s(60));
  ASSERT_EQ(full.code, 0) << full.err;
  const auto reference = files_under(reference_dir.path() / "out");
  ASSERT_EQ(reference.size(), 3u);  // summary.md, summary.json and index.html
  const double full_s = full.seconds;

  // Signals at moments spread over the whole run, from before main() to after the last rename:
  // whatever the timing, the invariant must hold. Counted: how many runs the signal really cut.
  int interrupted = 0, completed = 0, mid_run = 0;
  const int kTrials = 16;
  for (int trial = 0; trial < kTrials; ++trial) {
    ft::ScratchDir dir("fivebar_interrupt_run");
    std::ofstream(dir.path() / "scene.yaml") << scene;
    const int sig = trial % 2 == 0 ? SIGINT : SIGTERM;
    const double delay_s = full_s * 1.2 * trial / kTrials;
    ft::Child child = ft::spawn(FIVEBAR_BINARY, args, dir.path(), io.path());
    ASSERT_GT(child.pid, 0);
    std::this_thread::sleep_for(std::chrono::duration<double>(delay_s));
    ::kill(child.pid, sig);
    const ft::Outcome r = ft::wait(child, ft::child_timeout_s(60));
    SCOPED_TRACE("trial " + std::to_string(trial) + ", signal " + sigabbrev_np(sig) + " after " +
                 std::to_string(delay_s) + " s; stderr: " + r.err);
    ASSERT_FALSE(r.timed_out);
    if (r.signal != 0) {
      EXPECT_EQ(r.signal, sig);
      ++interrupted;
      if (fs::exists(dir.path() / "out" / "stress")) ++mid_run;  // after the run had started writing
    } else {
      EXPECT_EQ(r.code, 0);
      ++completed;
    }
    for (const auto& entry : ft::tree(dir.path())) {
      EXPECT_EQ(entry.find(".tmp."), std::string::npos) << "temporary left behind: " << entry;
    }
    const auto files = files_under(dir.path() / "out");
    for (const auto& [name, content] : files) {
      ASSERT_TRUE(reference.count(name)) << "unexpected file " << name;
      EXPECT_EQ(content.size(), reference.at(name).size()) << name << " is partial";
      EXPECT_TRUE(content == reference.at(name)) << name << " differs from the uninterrupted run";
    }
    if (r.signal == 0) EXPECT_EQ(files.size(), reference.size());
  }
  std::cout << "[ info ] full run " << full_s << " s; " << interrupted << " runs cut by the signal (" << mid_run
            << " of them after the output directory existed), " << completed << " completed first\n";
  EXPECT_GT(interrupted, 0);  // the first trials signal before the run can possibly end
}

}  // namespace
