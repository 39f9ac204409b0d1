// libFuzzer harness for the glTF reader and writer (see run_gltf in targets.hpp for the input format).
// An InputError is the expected answer to bad input; anything else is a finding.
#include "targets.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  tightex_fuzz::limit_threads();
  tightex_fuzz::obj_dir();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tightex_fuzz::or_abort("fuzz_gltf", [&] { tightex_fuzz::run_gltf(data, size); });
  return 0;
}
