#pragma once
/// Edits of a design file's text that keep the file: the value at a key path replaced where it is
/// written, every other byte (comments, order, spacing, quoting of other values) unchanged. Key
/// paths are resolved as fivebar/design/edit.hpp resolves them (docs/reliability.md "Key paths").
/// Behind the studio's Save (fivebar/studio.hpp, docs/studio.md).

#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace fivebar {

/// One edit: the scalar at `key` becomes `value`, a number (written in its shortest round-trip
/// form, fivebar/format.hpp `shortest`) or a string (written double-quoted, as the showcase writes
/// its modes).
struct FileEdit {
  std::string key;
  std::variant<double, std::string> value;
  bool operator==(const FileEdit&) const = default;
};

/// `text` (a design file named `origin` in messages) with every edit applied in order; a later
/// edit of the same key wins. InputError naming `origin` and the key when the text does not parse,
/// the key leads nowhere in it, to a map or a list, to an alias, or a number edit to a value that
/// is not a number; a value that is not finite is refused too. The result is not validated: load
/// it (load_design_from_string) for the design's rules, whose messages then name `origin` and the
/// unchanged line numbers.
std::string edit_design_text(std::string_view text, std::string_view origin, const std::vector<FileEdit>& edits);

}  // namespace fivebar
