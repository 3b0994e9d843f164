// The `bench:` section (fivebar/sections/bench.hpp): the bench files `fivebar run` fits the design to.
#include "fivebar/sections/bench.hpp"

#include "sections/rules.hpp"
#include "sections/section.hpp"

#include <atomic>

namespace fivebar {

namespace {
std::atomic<bool> outside_allowed{false};
}  // namespace

void allow_bench_paths_outside(bool allow) { outside_allowed.store(allow); }
bool bench_paths_outside_allowed() { return outside_allowed.load(); }

std::filesystem::path BenchSettings::resolve(const Design& design, const std::string& file) {
  const std::filesystem::path p(file);
  if (p.is_absolute() || design.source.empty()) return p;
  return design.source.parent_path() / p;
}

void BenchSettings::validate() const {
  for (const auto& [key, value] : {std::pair<const char*, const std::string*>{"calibration", &calibration},
                                   std::pair<const char*, const std::string*>{"identification", &identification}}) {
    if (value->find('\0') != std::string::npos) throw ValidationError(key, "must be a file name");
  }
  for (std::size_t k = 0; k < replay_logs.size(); ++k) {
    const std::string key = "replay_logs[" + std::to_string(k) + "]";
    if (replay_logs[k].empty() || replay_logs[k].find('\0') != std::string::npos) {
      throw ValidationError(key, "must be a file name, not empty");
    }
    // The outputs are named by the log's file name (bench_replay/<stem>-duties.csv).
    for (std::size_t i = 0; i < k; ++i) {
      if (std::filesystem::path(replay_logs[i]).stem() == std::filesystem::path(replay_logs[k]).stem()) {
        throw ValidationError(key, "= " + replay_logs[k] + ": replay_logs[" + std::to_string(i) + "] (" + replay_logs[i] +
                                       ") has the same file name without extension (the outputs are named by it)");
      }
    }
  }
  if (!(replay_tolerance >= 0.0) || !(replay_tolerance <= 2.0)) {
    throw ValidationError("replay_tolerance", "must be within [0, 2] (a duty difference)");
  }
}

void BenchSettings::check_inside(const Design& design, const std::string& key, const std::string& name) {
  if (name.empty() || design.source.empty() || bench_paths_outside_allowed()) return;
  std::error_code ec;
  const std::filesystem::path file = BenchSettings::resolve(design, name);
  if (!std::filesystem::exists(std::filesystem::symlink_status(file, ec))) return;  // missing: the product says so
  const std::filesystem::path parent = design.source.parent_path().empty() ? std::filesystem::path(".") : design.source.parent_path();
  const std::filesystem::path root = std::filesystem::weakly_canonical(parent, ec);
  const std::filesystem::path real = std::filesystem::weakly_canonical(file, ec);
  if (ec) return;
  const auto rel = real.lexically_relative(root);
  if (rel.empty() || *rel.begin() == "..") {
    // The target is not named: a refused file's place or content is not echoed.
    throw ValidationError(key, "= " + name + ": a symbolic link that leads out of the design file's folder (bench files stay beside the design)");
  }
}


void BenchSettings::require_inside(const Design& design, const std::string& key, const std::string& file) {
  try {
    check_inside(design, "bench." + key, file);
  } catch (const ValidationError& e) {
    throw InputError(design.source.generic_string() + ": " + e.what());
  }
}

namespace sections {
namespace {

/// A bench file stays beside the design (docs/bench-files.md "Where bench files may be"): a
/// relative path without a `..` component. A design shared by someone else cannot name
/// /etc/passwd or ~/.ssh/id_rsa for `fivebar run` to read.
void check_confined(const Value& v, const std::string& name) {
  if (bench_paths_outside_allowed()) return;
  const std::filesystem::path p(name);
  if (p.is_absolute() || (!name.empty() && (name.front() == '/' || name.front() == '~'))) {
    v.fail_value("must be a path relative to the design file's folder (bench files stay beside the design)");
  }
  for (const auto& part : p) {
    if (part == "..") v.fail_value("must not leave the design file's folder ('..'): bench files stay beside the design");
  }
}

void load(const Value& v, Design& design) {
  BenchSettings& b = design.set(BenchSettings{});
  if (v.is_null()) return;
  const auto all = v.entries({"calibration", "identification", "replay_logs", "replay_tolerance"},
                             "of bench files (calibration, identification, replay_logs, replay_tolerance)");
  if (const Value* c = find(all, "calibration")) b.calibration = c->text("must be a file name (CSV)");
  if (const Value* i = find(all, "identification")) b.identification = i->text("must be a file name (CSV)");
  if (const Value* c = find(all, "calibration"); c && b.calibration.empty()) c->fail_value("must be a file name, not empty");
  if (const Value* i = find(all, "identification"); i && b.identification.empty()) i->fail_value("must be a file name, not empty");
  if (const Value* c = find(all, "calibration")) check_confined(*c, b.calibration);
  if (const Value* i = find(all, "identification")) check_confined(*i, b.identification);
  if (const Value* r = find(all, "replay_logs")) {
    // One name, or a list of names.
    const std::vector<Value> names = r->is_scalar() ? std::vector<Value>{*r} : r->list("must be a list of file names (CSV)");
    if (names.empty()) r->fail("must name at least one log (or leave the key out)");
    for (const Value& n : names) {
      b.replay_logs.push_back(n.text("must be a file name (CSV)"));
      if (b.replay_logs.back().empty()) n.fail_value("must be a file name, not empty");
      check_confined(n, b.replay_logs.back());
    }
  }
  b.replay_tolerance = number_or(all, "replay_tolerance", b.replay_tolerance, "");
}

void check_links(const Design& design, const char* key, const std::string& name) { BenchSettings::check_inside(design, key, name); }

/// A log that is there but is a directory is a wrong name, not a missing file.
void check_replay_logs(const Design& design, const BenchSettings& b) {
  check_links(design, "calibration", b.calibration);
  check_links(design, "identification", b.identification);
  for (std::size_t k = 0; k < b.replay_logs.size(); ++k) {
    check_links(design, ("replay_logs[" + std::to_string(k) + "]").c_str(), b.replay_logs[k]);
  }
  for (std::size_t k = 0; k < b.replay_logs.size(); ++k) {
    std::error_code ec;
    const std::filesystem::path file = BenchSettings::resolve(design, b.replay_logs[k]);
    if (std::filesystem::is_directory(file, ec)) {
      throw ValidationError("replay_logs[" + std::to_string(k) + "]",
                            "= " + b.replay_logs[k] + ": is a directory (" + file.generic_string() + "), not a log file");
    }
  }
}

void validate(const Design& design) {
  const BenchSettings* b = design.get<BenchSettings>();
  if (b == nullptr) return;
  rules::validate_nested("bench", [&] {
    b->validate();
    check_replay_logs(design, *b);
  });
}

void write(const Design& design, Out& top) {
  const BenchSettings* b = design.get<BenchSettings>();
  if (b == nullptr) return;
  Out& o = top.add("bench", Out::map());
  if (!b->calibration.empty()) o.add("calibration", Out::quoted(b->calibration));
  if (!b->identification.empty()) o.add("identification", Out::quoted(b->identification));
  if (!b->replay_logs.empty()) {
    Out& logs = o.add("replay_logs", Out::list());
    for (const std::string& name : b->replay_logs) logs.push(Out::quoted(name));
  }
  if (b->replay_tolerance != 1e-9) o.add("replay_tolerance", Out::number(b->replay_tolerance));
}

}  // namespace

Section bench_section() { return {BenchSettings::kKey, &load, &validate, &write}; }

}  // namespace sections
}  // namespace fivebar
