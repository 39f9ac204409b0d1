// The library in a few lines: optimise a textured model's texture space with the defaults (the detail
// map, as many texels as the input uses, the least-squares fit, the input's image codec), write the
// result beside its report, and print what the report measured. Build: target tightex_example
// (CMakeLists.txt links tightex_lib). Usage: tightex_example INPUT OUTDIR
#include <cstdio>
#include <exception>

#include "tightex/run.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s INPUT OUTDIR\n", argv[0]);
    return 1;
  }
  try {
    tightex::Options options;  // size 0: the input's used texels
    options.progress = [](std::string_view stage, double fraction) {
      std::fprintf(stderr, "%.*s %3.0f%%\r", int(stage.size()), stage.data(), 100 * fraction);
      return true;  // false would cancel the run
    };
    const tightex::Report r = tightex::run(argv[1], argv[2], options);
    for (const std::string& w : r.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    std::printf("%s: %s, %dx%d texels, utilization %.1f%% -> %.1f%%, surface PSNR %.2f dB, %zu flipped, %zu lost\n", argv[1],
                r.model_path.c_str(), r.texture_sizes.at(0).first, r.texture_sizes.at(0).second, 100 * r.input_texels_used,
                100 * r.output_texels_used, r.surface_psnr_db, r.flipped_triangles, r.lost_triangles);
    return 0;
  } catch (const tightex::InputError& e) {  // bad input: one line naming the file and the problem
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error: %s\n", e.what());
    return 2;
  }
}
