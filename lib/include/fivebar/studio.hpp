#pragma once
/// The studio's state (docs/studio.md): a design file held open for editing by hand, its edits as
/// key paths and values (fivebar/design/file_edit.hpp), and one station's figures computed with
/// the library calls the command line makes (reachable regions, `fivebar coverage`, the priority
/// rule and collision map of `fivebar collision`, the LCI field of `fivebar workspace`). Behind
/// `fivebar studio`; it knows no HTTP.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/design/file_edit.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

/// Which figures one request computes. `live` is what a drag redraws (regions, coverage, poses,
/// outlines, the priority rule at the two tactor points); `quick` is `live` without computing the
/// priority rule (its search is most of a live answer: docs/studio.md "Speed"): `priority` is the
/// record when the cache holds it for these numbers, else "not certified yet", and the page asks
/// for it with studio_priority() in a second request; `full` adds the sampled figures (the
/// collision map over the target and the LCI field), which the page marks "not certified yet"
/// until their answer for the current edits has arrived.
enum class StudioFigures : std::uint8_t { live, full, quick };

/// Where the two tactors are held for the poses, outlines and the priority rule (mm, station
/// frame); unset: the target centre (the paper's worst case, `centre_rule` of the collision map).
struct StudioCursor {
  std::optional<Vec2> lower;
  std::optional<Vec2> upper;
};

/// What studio_figures() keeps between calls (docs/studio.md "Speed"): each mechanism's exact
/// region and its coverage of a target, the shared region of a pair and the priority rule at a
/// pair of points, each keyed by every number it is computed from, so that a drag of one
/// mechanism recomputes nothing of the other and a figure is never one of another state. A few
/// entries of each kind (the newest); safe to share between threads.
class StudioCache {
 public:
  StudioCache();
  ~StudioCache();
  StudioCache(const StudioCache&) = delete;
  StudioCache& operator=(const StudioCache&) = delete;
  struct Impl;
  Impl& impl() const { return *impl_; }  ///< for studio_figures()

 private:
  std::unique_ptr<Impl> impl_;
};

/// One station's figures as JSON (docs/studio.md "Figures"): station, cursor, target, mechanisms
/// (bases, links, modes, joint limits, exact region loops, pose and outline at the cursor),
/// shared region, coverage (the record of `fivebar coverage --json`), priority (the record of
/// `fivebar collision`'s rule), and with StudioFigures::full: collision_map (summary of
/// `fivebar collision --json`, sampled) and lci_field (sampled); otherwise those two are the
/// string "not certified yet". InputError when the station does not exist. With a `cache`, what
/// it holds for the same numbers is reused (the same figures, sooner).
Json studio_figures(const Design& design, std::string_view station, const StudioCursor& cursor = {},
                    StudioFigures which = StudioFigures::live, StudioCache* cache = nullptr);

/// The priority rule at the two tactor points of `station` (the `priority` figure of
/// studio_figures(): the record of `fivebar collision --upper --lower`, apply_priority()), or null
/// without both mechanisms and a `geometry:` section. Through `cache` (the entry a later
/// StudioFigures::quick answer of the same numbers shows). InputError when the station does not
/// exist.
Json studio_priority(const Design& design, std::string_view station, const StudioCursor& cursor = {},
                     StudioCache* cache = nullptr);

/// A pattern (stretch, slip, twist or pivot) played on the station as the design now is
/// (docs/studio.md "Patterns"): check_pattern() of pattern_spec() with the design's motor speed
/// limit, what `fivebar pattern --pattern KIND --json --samples` prints (the priority rule applied
/// sample by sample), plus `frames`: per sample the two linkages at their commanded points
/// ({lower, upper}: joints O1, A1, P, A2, O2 in mm, null when unreachable). InputError for an
/// unknown kind or station, a station without both mechanisms or a design without `geometry:`.
Json studio_pattern(const Design& design, std::string_view station, std::string_view kind);

/// The numbers and modes a page can edit, per station: key path, value, unit and a slider range
/// (for a length: 0.5 to 1.5 times its value; a coordinate: +- the station's length scale).
Json studio_controls(const Design& design);

/// The changed lines of `after` against `before` (same line count expected: in-place edits): a
/// list of {line, before, after}; when the counts differ, every line from the first difference.
Json line_diff(std::string_view before, std::string_view after);

/// A design file open in the studio: the text as read (or as last saved) and its hash.
class Studio {
 public:
  /// Reads and loads `file` with `rule` beside the loader's own (the command line passes
  /// validate_products of fivebar/scene.hpp, as load_scene does). InputError otherwise.
  explicit Studio(std::filesystem::path file, DesignRule rule = {});

  const std::filesystem::path& file() const { return file_; }
  const std::string& text() const { return text_; }
  /// SHA-256 of text(): what a save checks the file on disk against.
  const std::string& text_sha256() const { return sha_; }

  /// text() with `edits` applied (edit_design_text). InputError naming the file and key.
  std::string edited_text(const std::vector<FileEdit>& edits) const;
  /// The design with `edits` applied, loaded from the edited text: every rule of the loader, with
  /// its FILE:LINE: key messages (the lines are those of the file). InputError otherwise.
  Design design(const std::vector<FileEdit>& edits) const;
  /// The same design, sooner (what a drag asks for): the file as read is parsed once, and an edit
  /// of a number or mode that studio_controls() lists is set in a copy of that design with the
  /// design-edit API (fivebar/design/edit.hpp set_station_number) and the edited station checked
  /// with its rules (check_station_edit). Anything else (another key, a value of the wrong kind,
  /// a refused value) goes through design(), so a refusal gets the loader's FILE:LINE: key
  /// message. Used only when, on reading the file, setting every listed key both ways gave the
  /// same design (a file whose anchors tie two numbers together does not).
  Design live_design(const std::vector<FileEdit>& edits) const;
  /// True when live_design() sets edits in memory (see there); false: it loads every time.
  bool live_edits() const { return live_ != nullptr; }

  /// What a save would write: {file, sha256 (of the file as read), changes: line_diff, valid}.
  Json preview(const std::vector<FileEdit>& edits) const;

  /// Outcome of save().
  enum class SaveStatus : std::uint8_t { saved, changed_on_disk };
  /// Writes the edited text atomically (fivebar/io.hpp) when the file on disk still has the hash
  /// `expected_sha256` (the text the edits were made against); then text() is the saved text.
  /// changed_on_disk (nothing written) when it does not. InputError for edits the loader refuses
  /// (nothing written); IoError when the write fails.
  SaveStatus save(const std::vector<FileEdit>& edits, std::string_view expected_sha256);

  /// Re-reads the file from disk (after it changed there): InputError when it no longer loads.
  void reload();

 private:
  struct Live;  // the design as read and the keys live_design() sets in memory
  void prepare_live(Design base);

  std::filesystem::path file_;
  std::string text_;
  std::string sha_;
  DesignRule rule_;
  std::shared_ptr<const Live> live_;
};

}  // namespace fivebar
