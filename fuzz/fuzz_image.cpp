// libFuzzer harness for image decoding: decode_image on the raw bytes and image_dimensions on the same
// bytes as a file. An InputError is the expected answer to a bad image; anything else is a finding.
#include "targets.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  tightex_fuzz::limit_threads();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tightex_fuzz::or_abort("fuzz_image", [&] { tightex_fuzz::run_image(data, size); });
  return 0;
}
