// The `bench:` section (fivebar/sections/bench.hpp): the bench files `fivebar run` fits the design to.
#include "fivebar/sections/bench.hpp"

#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {

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
}

namespace sections {
namespace {

void load(const Value& v, Design& design) {
  BenchSettings& b = design.set(BenchSettings{});
  if (v.is_null()) return;
  const auto all = v.entries({"calibration", "identification"}, "of bench files (calibration, identification)");
  if (const Value* c = find(all, "calibration")) b.calibration = c->text("must be a file name (CSV)");
  if (const Value* i = find(all, "identification")) b.identification = i->text("must be a file name (CSV)");
  if (const Value* c = find(all, "calibration"); c && b.calibration.empty()) c->fail_value("must be a file name, not empty");
  if (const Value* i = find(all, "identification"); i && b.identification.empty()) i->fail_value("must be a file name, not empty");
}

void validate(const Design& design) {
  const BenchSettings* b = design.get<BenchSettings>();
  if (b == nullptr) return;
  rules::validate_nested("bench", [&] { b->validate(); });
}

void write(const Design& design, Out& top) {
  const BenchSettings* b = design.get<BenchSettings>();
  if (b == nullptr) return;
  Out& o = top.add("bench", Out::map());
  if (!b->calibration.empty()) o.add("calibration", Out::quoted(b->calibration));
  if (!b->identification.empty()) o.add("identification", Out::quoted(b->identification));
}

}  // namespace

Section bench_section() { return {BenchSettings::kKey, &load, &validate, &write}; }

}  // namespace sections
}  // namespace fivebar
