#pragma once
// Shared pieces of the `fivebar` subcommands: exit codes, DESIGN/--station/--mechanism handling,
// argument parsing with messages that name the option, CSV batch input and output formatting.
// No maths here: every number comes from lib/.

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <atomic>
#include <filesystem>
#include <functional>
#include <istream>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/io.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"

namespace fivebar::cli {

/// docs/conventions.md "Exit codes".
enum Exit : int {
  kOk = 0,           ///< success
  kCheckFailed = 1,  ///< a check failed / no solution
  kBadInput = 2,     ///< usage error or bad design file
  kInternal = 3,     ///< internal error (or the output could not be written)
};

/// Ends a subcommand's callback with `code` (CLI11's idiom: a RuntimeError carries the code).
void finish(int code);

// --- Design and mechanism selection -----------------------------------------------------------

/// DESIGN plus the --station / --mechanism choice, bound by add_target_options().
struct Target {
  std::string design;
  std::string station;
  std::string mechanism;
};
void add_design_argument(CLI::App& sub, std::string& design);
void add_target_options(CLI::App& sub, Target& target);

/// Loads DESIGN; InputError (exit 2) with the loader's file:line:key message on failure.
Design load(const std::string& path);

struct Selection {
  const Station* station = nullptr;
  const Mechanism* mechanism = nullptr;
  /// "index/lower"
  std::string label() const;
};
/// Resolves --station / --mechanism: an empty choice means "the only one present"; otherwise, or
/// for a name that is not there, InputError listing the choices.
Selection select(const Design& design, const Target& target);

/// While alive, SIGINT and SIGTERM set stop() instead of ending the process, so that a long
/// command (sweep, optimize) stops at its next checkpoint and says how to resume; the previous
/// handlers come back when it is destroyed. One at a time.
class StopOnInterrupt {
 public:
  StopOnInterrupt();
  ~StopOnInterrupt();
  StopOnInterrupt(const StopOnInterrupt&) = delete;
  StopOnInterrupt& operator=(const StopOnInterrupt&) = delete;
  const std::atomic<bool>* stop() const;

 private:
  struct Saved;
  std::unique_ptr<Saved> saved_;
};

/// Progress lines on stderr, only when it is a terminal (docs/conventions.md "Progress").
std::function<void(std::string_view)> terminal_progress(std::string_view command);

// --- Values -----------------------------------------------------------------------------------

/// "A,B" -> two finite numbers; InputError naming `option` and the expected form otherwise.
std::array<double, 2> parse_pair(std::string_view text, std::string_view option, std::string_view form);
/// "X,Y" -> a point in mm within the range of fivebar/ranges.hpp (the design files' rule).
std::array<double, 2> parse_point_mm(std::string_view text, std::string_view option);
/// "--shard K/N" -> (K, N) with 0 <= K < N; InputError naming --shard otherwise.
std::pair<std::uint64_t, std::uint64_t> parse_shard(const std::string& text);
/// "CX,CY,AX,AY,ANGLE" (mm, mm, full axes in mm, deg) -> an ellipse; InputError naming `option`.
Ellipse parse_ellipse(std::string_view text, std::string_view option = "--ellipse");
/// `s` without leading and trailing blanks.
std::string_view trim(std::string_view s);
/// The fields of `line` between `sep`, each trimmed.
std::vector<std::string_view> split(std::string_view line, char sep);
/// A finite number; std::nullopt when `text` is not exactly one.
std::optional<double> parse_number(std::string_view text);

// --- Output -----------------------------------------------------------------------------------

/// Where a command writes: `--out` is always the directory of the command's files; without it,
/// outputs/<design name>/<sub> (as `fivebar run` writes that product). Not created here.
std::filesystem::path command_output_dir(const std::string& out, const std::string& design_name, std::string_view sub);

/// The command line's words for a library remedy (fivebar/error.hpp): "--yes confirms it", ...;
/// empty for Remedy::none.
std::string remedy_hint(Remedy remedy);

/// The one JSON document of a --json run, on stdout.
void print_json(const Json& doc);
/// Fixed-point text ("-0.0000" shows as "0.0000").
std::string fixed(double value, int digits = 4);
/// Shortest text that reads back to the same double (CSV output).
std::string exact(double value);
/// Key/value table of one pose for human readers (angles in degrees, lengths in mm).
void print_pose(std::ostream& out, const Mechanism& m, const Pose& pose);
/// Compact description of the joint-limit verdict: "within", "OUTSIDE", "none set".
std::string limits_text(const Mechanism& m, const Pose& pose);

// --- The command scaffold ------------------------------------------------------------------------

/// A subcommand and its options object, which lives as long as the command's callback.
template <class Options>
struct Command {
  CLI::App* sub;
  Options* opt;
};

/// Adds the subcommand `name` to `parent` (the app, or a command with subcommands of its own such as
/// `report`) with a fresh `Options`; when it is chosen, its callback ends with finish(run(options)).
template <class Options, class Run>
Command<Options> add_command(CLI::App& parent, std::string name, std::string description, Run run) {
  auto opt = std::make_shared<Options>();
  CLI::App* sub = parent.add_subcommand(std::move(name), std::move(description));
  sub->callback([opt, run] { finish(run(*opt)); });
  return {sub, opt.get()};
}

/// -s,--station NAME: "Finger station (e.g. index, thumb); default: <when_absent>".
CLI::Option* add_station_option(CLI::App& sub, std::string& station, std::string_view when_absent);
/// -o,--out DIR: "Directory for <what> (default: outputs/<design>/<folder>)", where `folder` is the
/// one the command passes to command_output_dir() (docs/conventions.md "Output files").
CLI::Option* add_out_option(CLI::App& sub, std::string& out, std::string_view what, std::string_view folder);
/// --json: "Print <what> on stdout and nothing else" (docs/conventions.md "Streams").
CLI::Option* add_json_flag(CLI::App& sub, bool& json, std::string_view what = "one JSON document");

/// The words of a command's exit codes (docs/conventions.md "Exit codes").
struct ExitStatus {
  std::string_view ok = {};                  ///< 0
  std::string_view failed = {};              ///< 1; empty for a command with no check to fail
  std::string_view bad_input = "bad input";  ///< 2
  bool writes = false;                       ///< 3 also names output that could not be written
  bool resumable = false;                    ///< 130: interrupted, continued with --resume
};
/// "Exit status: 0 <ok>, 1 <failed>, 2 <bad_input>, 3 internal error[ or output not writable]."
std::string exit_status(const ExitStatus& status);

// --- Subcommands: one file each, listed in cli/commands.def ---------------------------------------
#define FIVEBAR_COMMAND(cmd) void setup_##cmd(CLI::App& app);
#include "commands.def"
#undef FIVEBAR_COMMAND

}  // namespace fivebar::cli
