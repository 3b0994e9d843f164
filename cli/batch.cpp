// The batch form of fk and ik (cli/batch.hpp).
#include "batch.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <numbers>

#include "common.hpp"
#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/ranges.hpp"

namespace fivebar::cli {

// --- Batch CSV --------------------------------------------------------------------------------

CsvReader::CsvReader(const std::string& path, std::vector<std::string> columns) : columns_(std::move(columns)) {
  if (path == "-") {
    name_ = "<stdin>";
    in_ = &std::cin;
  } else {
    name_ = path;
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw InputError(path + ": is a directory, not a CSV file");
    errno = 0;
    file_ = std::make_unique<std::ifstream>(path, std::ios::binary);
    if (!*file_) {
      const int err = errno;
      throw InputError("cannot open '" + path + "'" + (err != 0 ? std::string(": ") + std::strerror(err) : ""));
    }
    in_ = file_.get();
  }
  // The one bounded reader (fivebar/csv_reader.hpp) with the bench's bounds: 4096 bytes a line,
  // 1 GiB and 20,000,000 rows in all (docs/reliability.md "Resource bounds"), a duplicated column
  // refused, strict decimal numbers.
  reader_ = std::make_unique<csv::Reader>(*in_, name_);
  for (const auto& want : columns_) index_.push_back(reader_->require(want));
}

CsvReader::~CsvReader() = default;

bool CsvReader::next(std::vector<double>& values) {
  if (!reader_->next()) return false;
  values.resize(columns_.size());
  for (std::size_t k = 0; k < columns_.size(); ++k) {
    const double v = reader_->number(index_[k], std::numeric_limits<double>::max());
    // Lengths and coordinates (mm) obey the design files' range; angles only need to be finite.
    if (columns_[k].ends_with("_mm")) {
      if (const auto rule = ranges::coordinate_rule(v)) throw InputError(reader_->at(index_[k]) + *rule + " mm");
    }
    values[k] = v;
  }
  return true;
}

std::string CsvReader::where() const { return name_ + ":" + std::to_string(reader_->line()); }

BatchSink::BatchSink(const std::string& output_path) {
  if (!output_path.empty()) file_.emplace(output_path);
}

std::ostream& BatchSink::out() { return file_ ? file_->stream() : std::cout; }

void BatchSink::commit() {
  if (file_) {
    file_->commit();
  } else {
    std::cout.flush();
    if (!std::cout.good()) throw IoError("cannot write standard output: the write failed");
  }
}

CLI::Option* add_batch_options(CLI::App& sub, const std::string& name, const std::string& columns, CLI::Option* single,
                               std::string& file, std::string& output) {
  auto* opt = sub.add_option("--" + name + "-file", file,
                             "Batch: CSV with header columns " + columns +
                                 " ('-' = stdin); writes one CSV row per input row")
                  ->type_name("FILE");
  sub.add_option("-o,--output", output, "Batch: write the CSV to this file (atomically) instead of stdout")
      ->type_name("FILE");
  single->excludes(opt);
  return opt;
}

void require_single_or_batch(std::string_view command, const std::string& single, std::string_view single_usage,
                             const std::string& file, std::string_view file_flag, const std::string& output) {
  if (single.empty() == file.empty()) {
    throw InputError(std::string(command) + " needs exactly one of " + std::string(single_usage) + " or " +
                     std::string(file_flag) + " FILE");
  }
  if (!output.empty() && file.empty()) throw InputError("--output is for batch runs (" + std::string(file_flag) + ")");
}

BatchTally stream_batch(const std::string& file, std::vector<std::string> columns, const std::string& output,
                        const std::function<bool(const std::vector<double>& row, std::ostream& out)>& solve) {
  CsvReader reader(file, std::move(columns));
  BatchSink sink(output);
  std::ostream& out = sink.out();
  out << kBatchHeader << "\n";
  BatchTally tally;
  std::vector<double> row;
  while (reader.next(row)) {
    ++tally.rows;
    if (!solve(row, out)) ++tally.unsolved;
    // Stop at the first refused write (a full disk, a closed stdout) instead of computing the rest.
    if (!out.good()) {
      throw IoError("cannot write " + (output.empty() ? std::string("standard output") : "'" + output + "'") +
                    ": the write failed at row " + std::to_string(tally.rows) + " of " + file);
    }
  }
  sink.commit();
  return tally;
}

const char* const kBatchHeader = "x_mm,y_mm,theta1_deg,theta2_deg,status,lci,mode,assembly,within_joint_limits";

void write_batch_row(std::ostream& out, const Pose& pose, const std::optional<Vec2>& point_mm,
                     const std::optional<std::array<double, 2>>& theta_deg) {
  const bool exists = pose.status != Status::unreachable;
  std::string line;
  if (exists) {
    line = exact(pose.P.x()) + "," + exact(pose.P.y()) + "," + exact(angle_deg(pose.theta1)) + "," +
           exact(angle_deg(pose.theta2));
  } else {
    line = (point_mm ? exact(point_mm->x()) + "," + exact(point_mm->y()) : std::string(",")) + "," +
           (theta_deg ? exact((*theta_deg)[0]) + "," + exact((*theta_deg)[1]) : std::string(","));
  }
  line += "," + std::string(to_string(pose.status)) + "," + exact(pose.lci);
  if (exists) {
    line += "," + mode_string(pose.mode) + "," + std::string(1, sign_char(pose.assembly)) + "," +
            (pose.within_joint_limits ? "true" : "false");
  } else {
    line += ",,,";
  }
  line += '\n';
  out.write(line.data(), static_cast<std::streamsize>(line.size()));
}

}  // namespace fivebar::cli
