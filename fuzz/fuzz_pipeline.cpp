// libFuzzer harness for the whole method (tightex::optimize, then measure) on tiny meshes made from the
// bytes (format in targets.hpp). InputError is allowed. An InternalError, a lost or flipped triangle, or
// a component kept with its input UVs (the full method and the plain fallback both failed) is recorded
// as a finding and the run goes on (TIGHTEX_FUZZ_STRICT=1: abort instead); a crash, a
// sanitizer report, a broken output invariant or any other exception stops the run.
#include <string>

#include "targets.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  tightex_fuzz::limit_threads();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  tightex_fuzz::or_abort("fuzz_pipeline", [&] {
    try {
      const tightex_fuzz::PipelineOutcome r = tightex_fuzz::run_pipeline(data, size);
      if (r.lost > 0) tightex_fuzz::finding("lost", std::to_string(r.lost) + " lost triangles", data, size);
      if (r.flipped > 0) tightex_fuzz::finding("flipped", std::to_string(r.flipped) + " flipped triangles", data, size);
      // Not a broken promise (the component is output as it came), but the method failed on it twice.
      if (r.kept > 0) tightex_fuzz::finding("kept", r.kept_reason, data, size);
    } catch (const tightex::InternalError& e) {
      tightex_fuzz::finding("internal", e.what(), data, size);
    }
  });
  return 0;
}
