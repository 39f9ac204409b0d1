// Errors that name the culprit. Every failure a user can cause (bad file, bad value) is an InputError;
// a broken invariant inside tightex is an InternalError. The CLI maps them to exit codes 1 and 2.
#pragma once
#include <fmt/format.h>
#include <stdexcept>
#include <string>

namespace tightex {

enum class ExitCode : int { kOk = 0, kBadInput = 1, kInternal = 2 };

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class InternalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

template <typename... Args>
[[noreturn]] void fail_input(fmt::format_string<Args...> f, Args&&... args) {
  throw InputError(fmt::format(f, std::forward<Args>(args)...));
}

template <typename... Args>
[[noreturn]] void fail_internal(fmt::format_string<Args...> f, Args&&... args) {
  throw InternalError(fmt::format(f, std::forward<Args>(args)...));
}

}  // namespace tightex
