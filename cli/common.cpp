#include "fivebar/format.hpp"
#include "common.hpp"

#include "fivebar/ranges.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>

#include <unistd.h>

#include "fivebar/error.hpp"
#include "fivebar/json.hpp"

namespace fivebar::cli {

namespace {

std::string join(const std::vector<std::string>& items) { return format::join(items); }

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

std::vector<std::string_view> split(std::string_view line, char sep) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const auto pos = line.find(sep, start);
    out.push_back(trim(line.substr(start, pos == std::string_view::npos ? std::string_view::npos : pos - start)));
    if (pos == std::string_view::npos) break;
    start = pos + 1;
  }
  return out;
}

}  // namespace

void finish(int code) {
  if (code != kOk) throw CLI::RuntimeError(code);
}

// --- Design and mechanism selection -----------------------------------------------------------

void add_design_argument(CLI::App& sub, std::string& design) {
  sub.add_option("DESIGN", design, "Design/scene file (YAML), e.g. designs/iros2022.yaml")
      ->required()
      ->type_name("FILE");
}

void add_target_options(CLI::App& sub, Target& target) {
  add_design_argument(sub, target.design);
  sub.add_option("-s,--station", target.station,
                 "Finger station (e.g. index, thumb); default: the only one in the design")
      ->type_name("NAME");
  sub.add_option("-m,--mechanism", target.mechanism,
                 "Mechanism of the station: lower or upper; default: the only one present")
      ->check(CLI::IsMember({"lower", "upper"}))
      ->type_name("NAME");
}

Design load(const std::string& path) { return load_design(path); }

std::string Selection::label() const { return station->name + "/" + mechanism->name; }

Selection select(const Design& design, const Target& target) {
  Selection sel;
  std::vector<std::string> stations;
  for (const Station& s : design.stations) stations.push_back(s.name);
  if (target.station.empty()) {
    if (design.stations.size() != 1) {
      throw InputError("design '" + design.name + "' has " +
                       (stations.empty() ? std::string("no station") : "stations " + join(stations)) +
                       ": choose one with --station");
    }
    sel.station = &design.stations.front();
  } else {
    sel.station = &design.require_station(target.station);
  }
  std::vector<std::string> mechanisms;
  for (const Mechanism* m : sel.station->mechanisms()) mechanisms.push_back(m->name);
  if (target.mechanism.empty()) {
    if (mechanisms.size() != 1) {
      throw InputError("station '" + sel.station->name + "' has " +
                       (mechanisms.empty() ? std::string("no mechanism") : "mechanisms " + join(mechanisms)) +
                       ": choose one with --mechanism");
    }
    sel.mechanism = sel.station->mechanisms().front();
  } else {
    sel.mechanism = sel.station->mechanism(target.mechanism);
    if (sel.mechanism == nullptr) {
      throw InputError("station '" + sel.station->name + "' has no " + target.mechanism + " mechanism (it has: " +
                       (mechanisms.empty() ? std::string("none") : join(mechanisms)) + ")");
    }
  }
  return sel;
}

std::function<void(std::string_view)> terminal_progress(std::string_view command) {
  if (::isatty(STDERR_FILENO) == 0) return {};
  return [name = std::string(command)](std::string_view line) { std::cerr << "fivebar " << name << ": " << line << "\n"; };
}

// --- Values -----------------------------------------------------------------------------------

std::optional<double> parse_number(std::string_view text) {
  text = trim(text);
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

std::array<double, 2> parse_pair(std::string_view text, std::string_view option, std::string_view form) {
  const auto parts = split(text, ',');
  std::array<double, 2> out{};
  bool good = parts.size() == 2;
  for (std::size_t i = 0; good && i < 2; ++i) {
    const auto v = parse_number(parts[i]);
    good = v.has_value();
    if (good) out[i] = *v;
  }
  if (!good) {
    throw InputError(std::string(option) + " '" + std::string(text) + "': expected " + std::string(form) +
                     " (two finite numbers separated by a comma)");
  }
  return out;
}

std::array<double, 2> parse_point_mm(std::string_view text, std::string_view option) {
  const auto p = parse_pair(text, option, "X,Y in mm");
  for (double v : p) {
    if (const auto rule = ranges::coordinate_rule(v)) {
      throw InputError(std::string(option) + " '" + std::string(text) + "': coordinate " + exact(v) + " mm " + *rule +
                       " (docs/reliability.md \"Numeric ranges\")");
    }
  }
  return p;
}

std::pair<std::uint64_t, std::uint64_t> parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  std::uint64_t k = 0, n = 0;
  bool ok = slash != std::string::npos;
  if (ok) {
    const auto a = std::from_chars(text.data(), text.data() + slash, k);
    const auto b = std::from_chars(text.data() + slash + 1, text.data() + text.size(), n);
    ok = a.ec == std::errc{} && a.ptr == text.data() + slash && b.ec == std::errc{} &&
         b.ptr == text.data() + text.size() && slash > 0 && n > 0 && k < n;
  }
  if (!ok) throw InputError("--shard = '" + text + "': must be K/N with 0 <= K < N (e.g. 0/4)");
  return {k, n};
}

Ellipse parse_ellipse(std::string_view text, std::string_view option) {
  const std::string form = "CX,CY,AX,AY,ANGLE: centre (mm), full axis lengths (mm), rotation (deg)";
  auto fail = [&](const std::string& why) -> Ellipse {
    throw InputError(std::string(option) + " '" + std::string(text) + "': " + why + " (expected " + form + ")");
  };
  std::vector<double> v;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    std::string_view part = text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    while (!part.empty() && (part.front() == ' ' || part.front() == '\t')) part.remove_prefix(1);
    while (!part.empty() && (part.back() == ' ' || part.back() == '\t')) part.remove_suffix(1);
    if (!part.empty() && part.front() == '+') part.remove_prefix(1);
    double x = 0.0;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), x);
    if (part.empty() || ec != std::errc() || end != part.data() + part.size() || !std::isfinite(x)) {
      return fail("value " + std::to_string(v.size() + 1) + " '" + std::string(part) + "' is not a finite number");
    }
    v.push_back(x);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (v.size() != 5) return fail("got " + std::to_string(v.size()) + " numbers, need 5");
  if (!(v[2] > 0.0) || !(v[3] > 0.0)) return fail("axis lengths must be > 0");
  Ellipse e;
  e.center = {v[0], v[1]};
  e.axes = {v[2], v[3]};
  e.angle = v[4] * format::kRadPerDeg;
  try {
    e.validate();
  } catch (const InputError& err) {
    return fail(err.what());
  }
  return e;
}

// --- Output -----------------------------------------------------------------------------------

void print_json(const Json& doc) { std::cout << doc.dump(2) << "\n"; }

std::string fixed(double value, int digits) {
  char buf[64];
  // A value that would print as 0.000 though it is not zero, or as an integer of 16 or more
  // digits, is shown in scientific form instead ("1e-06", "1e+308").
  const double magnitude = std::fabs(value);
  if (std::isfinite(value) && value != 0.0 && (magnitude < 0.5 * std::pow(10.0, -digits) || magnitude >= 1e15)) {
    std::snprintf(buf, sizeof buf, "%.4g", value);
    return buf;
  }
  return format::fixed(value, digits);
}

std::string exact(double value) { return format::shortest(value); }

std::string limits_text(const Mechanism& m, const Pose& pose) {
  if (!m.joint_limits) return "none set";
  return pose.within_joint_limits ? "within" : "OUTSIDE";
}

void print_pose(std::ostream& out, const Mechanism& m, const Pose& pose) {
  constexpr double kDeg = format::kDegPerRad;
  const auto row = [&](std::string_view key, const std::string& value) {
    std::string k(key);
    k.resize(std::max<std::size_t>(k.size() + 2, 30), ' ');
    out << "  " << k << value << "\n";
  };
  row("status", std::string(to_string(pose.status)));
  if (pose.status == Status::unreachable) return;
  row("tactor P (mm)", fixed(pose.P.x()) + ", " + fixed(pose.P.y()));
  row("theta1, theta2 (deg)", fixed(angle_deg(pose.theta1)) + ", " + fixed(angle_deg(pose.theta2)));
  row("elbow A1 (mm)", fixed(pose.A1.x()) + ", " + fixed(pose.A1.y()));
  row("elbow A2 (mm)", fixed(pose.A2.x()) + ", " + fixed(pose.A2.y()));
  row("working mode (realised)", mode_string(pose.mode) + "   (design " + to_string(m.working_mode) + ")");
  row("assembly (realised)", std::string(1, sign_char(pose.assembly)) + "    (design " +
                                 to_string(m.assembly_mode) + ")");
  if (pose.jacobian_valid) {
    row("Jacobian dP/dtheta (mm/rad)", "[" + fixed(pose.J(0, 0)) + "  " + fixed(pose.J(0, 1)) + "]");
    row("", "[" + fixed(pose.J(1, 0)) + "  " + fixed(pose.J(1, 1)) + "]");
  } else {
    row("Jacobian dP/dtheta (mm/rad)", "undefined (type II singularity)");
  }
  row("LCI = 1/cond(J)", fixed(pose.lci));
  row("force capability (N/N*mm)", fixed(pose.force_capability));
  row("transmission (deg)", "elbow 1 " + fixed(pose.transmission[0] * kDeg, 2) + ", elbow 2 " +
                                fixed(pose.transmission[1] * kDeg, 2) + ", tactor " +
                                fixed(pose.transmission[2] * kDeg, 2));
  row("type I |sin| (legs 1, 2)", fixed(pose.type1_sin[0]) + ", " + fixed(pose.type1_sin[1]));
  row("type I distance (mm)", fixed(pose.type1_distance_mm));
  row("type II |sin|", fixed(pose.type2_sin));
  char closure[32];
  std::snprintf(closure, sizeof closure, "%.1e", pose.closure_error_mm);
  row("closure error (mm)", closure);
  row("joint limits", limits_text(m, pose));
}

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
  std::string header;
  if (!next_line(header)) throw InputError(name_ + ": empty, expected a header line with " + join(columns_));
  const auto names = split(header, ',');
  width_ = names.size();
  for (const auto& want : columns_) {
    std::size_t found = names.size();
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (names[i] == want) found = i;
    }
    if (found == names.size()) {
      throw InputError(where() + ": header has no column '" + want + "' (expected " + join(columns_) + ", got '" +
                       std::string(trim(header)) + "')");
    }
    index_.push_back(found);
  }
}

CsvReader::~CsvReader() = default;

namespace {

/// Longest CSV line read: far beyond any row of numbers, short enough that an endless stream
/// without line breaks (/dev/zero, a binary file) is refused instead of exhausting memory.
constexpr std::size_t kMaxCsvLineBytes = std::size_t{1} << 20;

/// std::getline with a length limit: false at the end of the stream, `too_long` set when the
/// line has more than kMaxCsvLineBytes bytes (the rest of the line is not read).
bool getline_bounded(std::istream& in, std::string& line, bool& too_long) {
  line.clear();
  too_long = false;
  std::streambuf* buf = in.rdbuf();
  if (buf == nullptr || !in.good()) return false;
  bool any = false;
  while (true) {
    const auto c = buf->sbumpc();
    if (std::char_traits<char>::eq_int_type(c, std::char_traits<char>::eof())) {
      in.setstate(std::ios::eofbit);
      return any;
    }
    any = true;
    if (std::char_traits<char>::to_char_type(c) == '\n') return true;
    if (line.size() >= kMaxCsvLineBytes) {
      too_long = true;
      return true;
    }
    line.push_back(std::char_traits<char>::to_char_type(c));
  }
}

}  // namespace

bool CsvReader::next_line(std::string& line) {
  bool too_long = false;
  while (getline_bounded(*in_, line, too_long)) {
    ++line_no_;
    if (too_long) {
      throw InputError(where() + ": line longer than " + std::to_string(kMaxCsvLineBytes) +
                       " bytes: not a CSV file of numbers");
    }
    const auto t = trim(line);
    if (t.empty() || t.front() == '#') continue;
    return true;
  }
  if (in_->bad()) throw InputError(name_ + ": read error after line " + std::to_string(line_no_));
  return false;
}

bool CsvReader::next(std::vector<double>& values) {
  std::string line;
  if (!next_line(line)) return false;
  const auto fields = split(line, ',');
  if (fields.size() < width_) {
    throw InputError(where() + ": " + std::to_string(fields.size()) + " fields, the header has " +
                     std::to_string(width_));
  }
  values.resize(columns_.size());
  for (std::size_t k = 0; k < columns_.size(); ++k) {
    const auto v = parse_number(fields[index_[k]]);
    if (!v) {
      throw InputError(where() + ": " + columns_[k] + " = '" + std::string(fields[index_[k]]) +
                       "' is not a finite number");
    }
    // Lengths and coordinates (mm) obey the design files' range; angles only need to be finite.
    if (columns_[k].ends_with("_mm")) {
      if (const auto rule = ranges::coordinate_rule(*v)) {
        throw InputError(where() + ": " + columns_[k] + " = " + exact(*v) + " " + *rule);
      }
    }
    values[k] = *v;
  }
  return true;
}

std::string CsvReader::where() const { return name_ + ":" + std::to_string(line_no_); }

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
