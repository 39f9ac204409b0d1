// Throwing the errors of tightex/error.hpp with a formatted message; the CLI's exit codes for them.
#pragma once
#include <fmt/format.h>

#include <string>

#include "tightex/error.hpp"

namespace tightex {

enum class ExitCode : int { kOk = 0, kBadInput = 1, kInternal = 2 };

template <typename... Args>
[[noreturn]] void fail_input(fmt::format_string<Args...> f, Args&&... args) {
  throw InputError(fmt::format(f, std::forward<Args>(args)...));
}

template <typename... Args>
[[noreturn]] void fail_internal(fmt::format_string<Args...> f, Args&&... args) {
  throw InternalError(fmt::format(f, std::forward<Args>(args)...));
}

}  // namespace tightex
