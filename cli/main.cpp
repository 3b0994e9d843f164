// fivebar: command-line front end, fivebar::cli::main (cli/cli.hpp). Subcommands live in one file
// each (setup_<cmd> / run_<cmd>), listed in cli/commands.def; this file maps every outcome to the
// exit codes of docs/conventions.md. The process entry point is fivebar_main.cpp; the fuzzer (test/fuzz/fuzz_cli.cpp) calls this in-process.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include "cli.hpp"
#include "common.hpp"
#include "help.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/sections/bench.hpp"
#include "fivebar/version.hpp"

namespace {

/// CLI11 reads "-+" or "-.5,2" after an option as an option of its own. Values of the options
/// below often start with '-' (modes, branches, negative numbers), so "--mode -+" is rewritten
/// to "--mode=-+" before parsing.
std::vector<std::string> join_dash_values(int argc, char** argv) {
  static const std::set<std::string> takes_value{"-t",      "--theta",   "-p",        "--point",   "--mode",
                                                 "-b",      "--branch",  "--ellipse", "--spacing", "--upper",
                                                 "--lower", "--center"};
  std::vector<std::string> args(argv + 1, argv + argc);
  std::vector<std::string> out;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (takes_value.count(a) > 0 && i + 1 < args.size()) {
      const std::string& v = args[i + 1];
      const bool dash_value = !v.empty() && v[0] == '-' && (v.size() == 1 || !std::isalpha(static_cast<unsigned char>(v[1])));
      if (dash_value) {
        // Short forms take "-bVALUE"; long forms "--opt=VALUE".
        out.push_back(a.size() == 2 ? a + v : a + "=" + v);
        ++i;
        continue;
      }
    }
    out.push_back(a);
  }
  return out;
}

/// docs/reliability.md: every numeric flag of every command refuses, as bad input (exit 2), what
/// is not a finite number of its type: `nan`, `inf`, an overflow (`1e999`), a negative or
/// fractional value for a count or a seed (CLI11 would wrap `--seed -1` to 2^64 - 1). Numeric
/// options are known by their value name: CLI11's FLOAT, INT and UINT, and the unit names the
/// commands give theirs (S, N, PX, DEG, HZ, R).
std::string numeric_flag_error(const std::string& type, const std::string& text) {
  const bool whole = type == "UINT" || type == "INT" || type == "N";
  const bool unsigned_only = type == "UINT" || type == "N";
  std::string t = text;
  while (!t.empty() && (t.front() == ' ' || t.front() == '\t')) t.erase(t.begin());
  while (!t.empty() && (t.back() == ' ' || t.back() == '\t')) t.pop_back();
  if (t.empty()) return "'" + text + "': not a number";
  if (whole) {
    const bool negative = t.front() == '-';
    if (negative && unsigned_only) return "'" + t + "': must be a whole number >= 0";
    const std::size_t digits = t.find_first_not_of("0123456789", (negative || t.front() == '+') ? 1 : 0);
    if (digits != std::string::npos || t.size() == ((negative || t.front() == '+') ? 1u : 0u)) {
      return "'" + t + "': must be a whole number";
    }
    errno = 0;
    char* end = nullptr;
    if (negative) (void)std::strtoll(t.c_str(), &end, 10);
    else (void)std::strtoull(t.c_str(), &end, 10);
    if (errno == ERANGE) return "'" + t + "': too large";
    return "";
  }
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (end == t.c_str() || *end != '\0') return "'" + t + "': not a number";
  if (!std::isfinite(v) || (errno == ERANGE && std::fabs(v) > 1.0)) return "'" + t + "': must be a finite number";
  return "";
}

void guard_numeric_flags(CLI::App& app) {
  static const std::set<std::string> numeric{"FLOAT", "INT", "UINT", "S", "N", "PX", "DEG", "HZ", "R"};
  for (CLI::Option* option : app.get_options()) {
    std::string type = option->get_type_name();  // "INT" or "INT:<a validator's description>"
    type = type.substr(0, type.find(':'));
    if (numeric.count(type) == 0 || option->get_type_size() != 1) continue;
    option->check(CLI::Validator([type](std::string& value) { return numeric_flag_error(type, value); }, "", "finite"));
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) guard_numeric_flags(*sub);
}

/// docs/bench-files.md "Where bench files may be": the files a design's `bench:` section names
/// stay in the design file's folder unless the command says otherwise. One flag, the same on every
/// command (each loads designs, and `run` reads their bench files).
void add_outside_paths_flag(CLI::App& app) {
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    if (sub->get_subcommands([](CLI::App*) { return true; }).empty()) {
      sub->add_flag_callback("--allow-outside-paths", [] { fivebar::allow_bench_paths_outside(true); },
                             "Read the files a design's bench: section names even outside the design file's folder "
                             "(absolute, '..', or a link leading out; refused without this flag)");
    } else {
      add_outside_paths_flag(*sub);
    }
  }
}

}  // namespace

namespace fivebar::cli {
namespace {

/// Flushes standard output and reports what the kernel refused (a full disk, a closed or broken
/// descriptor): a lost result is an error, exit 3, whatever the command's own outcome was.
int finish_stdout(int code) {
  std::cout.flush();
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int error = errno;
  if (std::cout.good() && flushed && std::ferror(stdout) == 0) return code;
  std::cerr << "fivebar: error: cannot write standard output: "
            << (error != 0 ? std::string(std::strerror(error)) : std::string("the write failed (a full disk, or standard output closed)"))
            << "\n";
  std::cout.clear();
  std::clearerr(stdout);
  return kInternal;
}

int run(int argc, char** argv);

}  // namespace

int main(int argc, char** argv) { return finish_stdout(run(argc, argv)); }

namespace {

int run(int argc, char** argv) {
  CLI::App app{
      "fivebar " + std::string(fivebar::version()) +
          ": design five-bar-linkage cutaneous haptic devices (IROS 2022).\n"
          "Lengths in mm and angles in degrees on the command line, in files and in JSON.",
      "fivebar"};
  app.set_version_flag("-V,--version", "fivebar " + std::string(fivebar::version()));
  app.require_subcommand(1);
  app.footer("Run 'fivebar help <subcommand>' (or 'fivebar <subcommand> --help') for its options.\n" +
             exit_status({.ok = "success",
                          .failed = "a check failed or no solution",
                          .bad_input = "bad input (usage or design file)"}));
  // One subcommand per line of cli/commands.def, in its order.
#define FIVEBAR_COMMAND(cmd) setup_##cmd(app);
#include "commands.def"
#undef FIVEBAR_COMMAND
  // After every subcommand: their numeric flags refuse NaN, infinities and overflow.
  guard_numeric_flags(app);
  add_outside_paths_flag(app);
  fivebar::allow_bench_paths_outside(false);  // per run: the fuzzer calls this in-process

  try {
    std::vector<std::string> args = join_dash_values(argc, argv);
    // `fivebar help [CMD [SUB]]`, `help --completion bash|zsh`, `help --man [CMD]` (cli/help.hpp).
    if (!args.empty() && args[0] == "help") return run_help(app, std::vector<std::string>(args.begin() + 1, args.end()));
    // CLI11 says only "A subcommand is required" for an unknown word where a subcommand must be
    // (fivebar WORD, fivebar report WORD): name the word and the choices.
    CLI::App* level = &app;
    std::string path;
    for (const std::string& word : args) {
      if (word.empty() || word[0] == '-' || level->get_require_subcommand_min() == 0) break;
      std::string known;
      CLI::App* match = nullptr;
      for (CLI::App* sub : level->get_subcommands([](CLI::App*) { return true; })) {
        if (sub->check_name(word)) match = sub;
        known += (known.empty() ? "" : ", ") + sub->get_name();
      }
      if (match == nullptr) {
        std::string shown;  // a word from the command line must not bring terminal escapes along
        for (const char c : word) shown += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? '?' : c;
        std::vector<std::string> names;
        for (CLI::App* sub : level->get_subcommands([](CLI::App*) { return true; })) names.push_back(sub->get_name());
        const std::string near = did_you_mean(word, names);
        throw fivebar::InputError("unknown subcommand '" + shown + "'" + (path.empty() ? "" : " of '" + path + "'") +
                                  (near.empty() ? "" : " (did you mean '" + near + "'?)") + " (known: " + known + ")");
      }
      path += (path.empty() ? "" : " ") + match->get_name();
      level = match;
    }
    std::reverse(args.begin(), args.end());  // CLI11 consumes a reversed vector
    app.parse(args);
    return kOk;
  } catch (const CLI::RuntimeError& e) {  // a subcommand's own exit code (see finish())
    return e.get_exit_code();
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    print_parse_error(app, e);  // "fivebar CMD: error: ...", with the nearest option for an unknown one
    return kBadInput;
  } catch (const fivebar::InputError& e) {
    std::cerr << "fivebar: error: " << e.what() << "\n";
    if (const std::string hint = fivebar::cli::remedy_hint(e.remedy()); !hint.empty()) {
      std::cerr << "fivebar: hint: " << hint << "\n";
    }
    return kBadInput;
  } catch (const fivebar::IoError& e) {
    std::cerr << "fivebar: error: " << e.what() << "\n";
    return kInternal;
  } catch (const std::exception& e) {
    std::cerr << "fivebar: internal error: " << e.what() << "\n";
    return kInternal;
  } catch (...) {
    std::cerr << "fivebar: internal error: unknown exception\n";
    return kInternal;
  }
}

}  // namespace
}  // namespace fivebar::cli
