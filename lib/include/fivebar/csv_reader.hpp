#pragma once
/// The one reader of the bench's CSV files and of the device log (docs/bench-files.md): the
/// calibration measurements, the hard-stop readings, the device log that `replay`, `identify` and
/// `bench.replay_logs` read. Bounded whatever the input (a file, a pipe, /dev/zero): at most
/// Limits::max_line bytes a line, Limits::max_bytes in all and Limits::max_rows data rows, each
/// checked while reading, so nothing larger than one line is held before a refusal. Blank lines
/// and lines starting with '#' are skipped anywhere; line breaks may be LF or CR LF; a UTF-8 byte
/// order mark before the header is dropped. Cells are separated by commas, trimmed of blanks and
/// may be quoted as the writers quote them (RFC 4180). The header names every column once (an
/// empty or duplicated name is refused) and every data row has as many cells as the header.
/// Every refusal is an InputError "ORIGIN:LINE: column 'NAME': ..." that shows at most 40
/// characters of the cell, control characters escaped.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <istream>
#include <string>
#include <string_view>
#include <vector>

namespace fivebar::csv {

/// Largest |cell| of a bench file or device log in its unit (SI, or mm for a `*_mm` column): no
/// bench quantity comes near it, and every product of the fits stays finite.
inline constexpr double kMaxBenchValue = 1e9;

/// Bounds of one file (refused beyond them, never truncated).
struct Limits {
  std::size_t max_line = 4096;              ///< bytes per line, line break excluded
  std::uintmax_t max_bytes = 1ull << 30;    ///< bytes in all
  std::size_t max_rows = 20'000'000;        ///< data rows (header and skipped lines excluded)
};

class Reader {
 public:
  /// Reads up to and including the header; InputError for an empty file or a bad header.
  Reader(std::istream& in, std::string origin, Limits limits = {});

  const std::vector<std::string>& header() const { return header_; }
  std::size_t header_line() const { return header_line_; }
  /// Index of the column `name`, or -1.
  int column(std::string_view name) const;
  /// Index of the column `name`; InputError at the header's line when it is missing.
  std::size_t require(std::string_view name) const;

  /// Moves to the next data row; false at the end of the input.
  bool next();
  std::size_t line() const { return line_; }  ///< line of the current row (1-based)
  std::size_t rows() const { return rows_; }  ///< data rows read so far
  const std::vector<std::string>& cells() const { return cells_; }
  const std::string& cell(std::size_t c) const { return cells_[c]; }
  /// The current row's line as read (line break and a CR before it removed).
  const std::string& text() const { return buffer_; }

  /// The cell as a finite number: decimal or scientific notation only (no hexadecimal `0x10`, no
  /// trailing text `41496junk`, no inf or nan), |v| <= max_abs. InputError "ORIGIN:LINE: column
  /// 'NAME' = 'CELL': ..." otherwise; `unit` (may be empty) is named in the message.
  double number(std::size_t c, double max_abs, std::string_view unit = {}) const;
  /// "ORIGIN:LINE: " of the current row (the header's before the first next()).
  std::string where() const;
  /// "ORIGIN:LINE: column 'NAME' = 'CELL': " of a cell of the current row.
  std::string at(std::size_t c) const;
  const std::string& origin() const { return origin_; }

 private:
  bool read_line(std::string& out);  // one physical line, bounded
  std::vector<std::string> split(const std::string& line) const;

  std::istream& in_;
  std::string origin_;
  Limits limits_;
  std::vector<std::string> header_, cells_;
  std::size_t header_line_ = 0, line_ = 0, rows_ = 0;
  std::uintmax_t bytes_ = 0;
  std::string buffer_;
};

/// At most 40 characters of `text`, control characters and DEL escaped as \xNN (for messages).
std::string shown(std::string_view text);

/// A whole file read with a bound (for files that are hashed as well as parsed): InputError
/// naming the file when it cannot be read or holds more than `max_bytes` (checked while reading:
/// /dev/zero is refused after max_bytes + 1 bytes). `what` names the file in messages.
std::string read_bounded(const std::filesystem::path& path, std::uintmax_t max_bytes, std::string_view what);

}  // namespace fivebar::csv
