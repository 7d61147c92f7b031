// error.h: how glaze reports problems.
//
// Anything the user can cause (a missing file, a malformed map, a bad option) throws
// glaze::Error with a message that names the input, says what is wrong and, where
// possible, what to do. The command line prints it and exits non-zero. Warnings go
// through one replaceable sink so that tests can observe them.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>

namespace glaze {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

using WarningSink = std::function<void(const std::string&)>;

// Emits a warning (default: "glaze: warning: ..." on stderr).
void warn(const std::string& message);

// The same, the first time this exact message is given in this process only (for
// warnings that every call of a routine would repeat).
void warn_once(const std::string& message);

// Replaces the warning sink; returns the previous one. Not thread-safe: set it up front.
WarningSink set_warning_sink(WarningSink sink);

}  // namespace glaze
