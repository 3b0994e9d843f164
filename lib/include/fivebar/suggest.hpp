#pragma once
/// "Did you mean" for a mistyped name (a key of a design file, an option, a subcommand).

#include <string>
#include <string_view>
#include <vector>

namespace fivebar {

/// The choice nearest to `word`: the fewest single-character edits (Levenshtein), at most
/// max(2, |word| / 3), ties to the first; else the only choice that `word` is a prefix of; else "".
std::string nearest_name(std::string_view word, const std::vector<std::string>& choices);

}  // namespace fivebar
