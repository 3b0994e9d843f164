#pragma once
/// Exception types. Caller input errors (design files, command-line values) throw InputError;
/// expected outcomes (unreachable point, singular pose) are statuses, never exceptions.

#include <stdexcept>
#include <string>

namespace fivebar {

/// Bad caller input. what() is a complete message: "FILE:LINE: key 'K' = V: rule".
class InputError : public std::invalid_argument {
 public:
  explicit InputError(const std::string& message) : std::invalid_argument(message) {}
};

}  // namespace fivebar
