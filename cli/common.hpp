#pragma once
// Shared pieces of the `fivebar` subcommands: exit codes, DESIGN/--station/--mechanism handling,
// argument parsing with messages that name the option, CSV batch input and output formatting.
// No maths here: every number comes from lib/.

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <functional>
#include <istream>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
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
/// A finite number; std::nullopt when `text` is not exactly one.
std::optional<double> parse_number(std::string_view text);

// --- Output -----------------------------------------------------------------------------------

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

// --- Batch CSV --------------------------------------------------------------------------------

/// Reads a CSV with a header line, streaming: only the current row is held. Columns are found by
/// name (extra columns are ignored, so a previous command's output can be fed back). Blank lines
/// and lines starting with '#' are skipped; '-' reads stdin. Errors are InputError "FILE:LINE: ...".
class CsvReader {
 public:
  CsvReader(const std::string& path, std::vector<std::string> columns);
  ~CsvReader();
  /// The next row's values of the requested columns, in the requested order; false at the end.
  bool next(std::vector<double>& values);
  /// "FILE:LINE" of the row last returned.
  std::string where() const;

 private:
  bool next_line(std::string& line);
  std::string name_;
  std::unique_ptr<std::istream> file_;
  std::istream* in_ = nullptr;
  std::size_t line_no_ = 0;
  std::vector<std::string> columns_;
  std::vector<std::size_t> index_;
  std::size_t width_ = 0;
};

/// Where batch rows go: stdout, or an atomically written file (--output).
class BatchSink {
 public:
  explicit BatchSink(const std::string& output_path);
  std::ostream& out();
  /// Commits the file (no-op for stdout). Without it the file is discarded.
  void commit();

 private:
  std::optional<AtomicFile> file_;
};

/// The batch form's options beside the single form `single`: `--<name>-file FILE` (a CSV with
/// header columns `columns`, '-' = stdin) and -o/--output. Returns the file option, for excludes().
CLI::Option* add_batch_options(CLI::App& sub, const std::string& name, const std::string& columns, CLI::Option* single,
                               std::string& file, std::string& output);

/// Exactly one of the single form (`single`, shown as `single_usage`) and the batch file
/// (`file`, option `file_flag`), and --output only with the file; InputError otherwise.
void require_single_or_batch(std::string_view command, const std::string& single, std::string_view single_usage,
                             const std::string& file, std::string_view file_flag, const std::string& output);

/// Streams the batch form: reads `file` row by row and writes kBatchHeader and one row per input
/// row through `solve`, which writes its row and returns whether it has a solution. The output
/// (stdout, or the --output file, atomically) is committed after the last row; a bad row throws
/// before that. Returns how many rows were read and how many had no solution.
struct BatchTally {
  std::size_t rows = 0, unsolved = 0;
};
BatchTally stream_batch(const std::string& file, std::vector<std::string> columns, const std::string& output,
                        const std::function<bool(const std::vector<double>& row, std::ostream& out)>& solve);

/// Header and one row of batch output: x_mm,y_mm,theta1_deg,theta2_deg,status,lci,mode,assembly,
/// within_joint_limits. For an unreachable row the known inputs are echoed and the rest left empty.
extern const char* const kBatchHeader;
void write_batch_row(std::ostream& out, const Pose& pose, const std::optional<Vec2>& point_mm,
                     const std::optional<std::array<double, 2>>& theta_deg);

// --- Subcommands (one file each) ----------------------------------------------------------------
void setup_fk(CLI::App& app);
void setup_ik(CLI::App& app);
void setup_sweep(CLI::App& app);
void setup_run(CLI::App& app);
void setup_workspace(CLI::App& app);
void setup_coverage(CLI::App& app);
void setup_parts(CLI::App& app);
void setup_collision(CLI::App& app);
void setup_pattern(CLI::App& app);
void setup_report(CLI::App& app);
void setup_export(CLI::App& app);

}  // namespace fivebar::cli
