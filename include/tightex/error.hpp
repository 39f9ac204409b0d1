// The errors tightex throws. Every failure a user can cause (bad file, bad value) is an InputError
// whose message names the file, the element and the problem; a broken invariant inside tightex is an
// InternalError (a bug: please report it with the input); a run the progress callback stopped ends in
// Cancelled.
#pragma once
#include <stdexcept>

namespace tightex {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class InternalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
/// Thrown once a progress callback returned false (Options::progress): the run stops, nothing is written.
class Cancelled : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace tightex
