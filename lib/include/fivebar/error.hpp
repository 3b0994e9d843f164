#pragma once
/// Exception types. Caller input errors (design files, command-line values) throw InputError;
/// expected outcomes (unreachable point, singular pose) are statuses, never exceptions.

#include <stdexcept>
#include <string>

namespace fivebar {

/// What the caller can do about a refusal, named without an interface: the library's messages
/// speak of the design's keys and the option structs, and the command line (cli/main.cpp) adds
/// its own flag for the remedy (`--yes`, `--no-render`, ...), the Python module its keyword.
enum class Remedy {
  none,
  confirm,            ///< the work is large: confirm it (SweepOptions::confirmed, ...)
  start_afresh,       ///< what exists cannot be resumed: start again without resuming
  without_rendering,  ///< a tool is missing: the sources can be written without it
  resume_shard,       ///< a shard was interrupted: resume that shard before merging
  longer_budget,      ///< the wall-time budget ran out: give it more seconds
};

/// Bad caller input. what() is a complete message: "FILE:LINE: key 'K' = V: rule".
class InputError : public std::invalid_argument {
 public:
  explicit InputError(const std::string& message, Remedy remedy = Remedy::none)
      : std::invalid_argument(message), remedy_(remedy) {}
  /// What the caller can do about it (Remedy::none: fix the input).
  Remedy remedy() const noexcept { return remedy_; }

 private:
  Remedy remedy_;
};

}  // namespace fivebar
