// libFuzzer harness for the PLY reader (see run_ply in targets.hpp for the input format).
// An InputError is the expected answer to bad input; anything else is a finding.
#include "targets.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  tightex_fuzz::limit_threads();
  tightex_fuzz::obj_dir();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tightex_fuzz::or_abort("fuzz_ply", [&] { tightex_fuzz::run_ply(data, size); });
  return 0;
}
