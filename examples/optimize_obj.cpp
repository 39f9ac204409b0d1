// The library in a few lines: read a textured OBJ, optimise its texture space with the defaults (the
// detail map, as many texels as the input uses, the least-squares fit), write the result and print
// what the report measured. Build: target tightex_example (CMakeLists.txt links tightex_lib).
// Usage: tightex_example INPUT.obj OUTDIR
#include <cstdio>
#include <exception>
#include <filesystem>

#include "tightex/tightex.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s INPUT.obj OUTDIR\n", argv[0]);
    return 1;
  }
  try {
    const tightex::TexturedMesh input = tightex::read_obj(argv[1]);  // textures decoded too
    tightex::Options options;                                        // size 0: the input's used texels
    options.progress = [](std::string_view stage, double fraction) {
      std::fprintf(stderr, "%.*s %3.0f%%\r", int(stage.size()), stage.data(), 100 * fraction);
      return true;  // false would cancel the run
    };
    const tightex::Result result = tightex::optimize(input, options);
    std::filesystem::create_directories(argv[2]);
    tightex::write_obj(result.output, argv[2], std::filesystem::path(argv[1]).stem().string(), tightex::ImageFormat::kPng);
    const auto& m = result.report["metrics"];
    std::printf("%s: %d² texels, utilization %.1f%% -> %.1f%%, surface PSNR %.2f dB, %d flipped, %d lost\n", argv[1],
                result.report["options"]["size"].get<int>(), 100 * m["input"]["utilization"].get<double>(),
                100 * m["output"]["utilization"].get<double>(), m["surface_psnr_db"].get<double>(), m["flipped"].get<int>(),
                m["lost_triangles"].get<int>());
    return 0;
  } catch (const tightex::InputError& e) {  // bad input: one line naming the file and the problem
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error: %s\n", e.what());
    return 2;
  }
}
