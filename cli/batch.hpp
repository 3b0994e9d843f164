#pragma once
// The batch form of fk and ik (--theta-file / --point-file, -o/--output): a CSV streamed in, one
// CSV row out per row in, through stdout or an atomically written file. Private to cli/.

#include <CLI/CLI.hpp>

#include <array>
#include <functional>
#include <istream>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/io.hpp"
#include "fivebar/kinematics.hpp"

namespace fivebar::csv {
class Reader;
}  // namespace fivebar::csv

namespace fivebar::cli {

// --- Batch CSV --------------------------------------------------------------------------------

/// Reads a CSV with a header line, streaming: only the current row is held. Columns are found by
/// name (extra columns are ignored, so a previous command's output can be fed back). Read by the
/// one bounded reader, fivebar/csv_reader.hpp (its syntax, bounds and messages); '-' reads stdin.
/// Errors are InputError "FILE:LINE: column 'NAME' = 'CELL': ...".
class CsvReader {
 public:
  CsvReader(const std::string& path, std::vector<std::string> columns);
  ~CsvReader();
  /// The next row's values of the requested columns, in the requested order; false at the end.
  bool next(std::vector<double>& values);
  /// "FILE:LINE" of the row last returned.
  std::string where() const;

 private:
  std::string name_;
  std::unique_ptr<std::istream> file_;
  std::istream* in_ = nullptr;
  std::unique_ptr<csv::Reader> reader_;
  std::vector<std::string> columns_;
  std::vector<std::size_t> index_;
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

}  // namespace fivebar::cli
