// tightex_make_genus: writes the generated surfaces of tests/genus_surfaces.hpp as OBJ + MTL + PNG, so
// the CLI (and bench/run_data.sh-like loops) can run on them: the paper's extreme case (every triangle
// its own texture space) at genus 1..25.
//
//   tightex_make_genus OUTDIR
//
// writes OUTDIR/plate_g<G>/plate_g<G>.obj for G in kPlateGenera and OUTDIR/arches_g<G>/arches_g<G>.obj
// for G in kArchGenera.
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>

#include "genus_surfaces.hpp"
#include "io/obj_writer.hpp"

int main(int argc, char** argv) {
  // An option is never an output folder: `tightex_make_genus --help` once wrote the catalogue into a
  // folder named "--help".
  if (argc != 2 || argv[1][0] == '-') {
    std::fprintf(stderr, "usage: %s OUTDIR\n", argv[0]);
    return argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") ? 0 : 1;
  }
  try {
    namespace cat = tightex::testing;
    auto write = [&](tightex::TexturedMesh m) {
      m.textures[0].path = m.source + "_texture";  // a file stem: write_obj appends .png
      const std::string dir = std::string(argv[1]) + "/" + m.source;
      std::filesystem::create_directories(dir);
      tightex::write_obj(m, dir, m.source, tightex::ImageFormat::kPng);
    };
    for (int g : cat::kPlateGenera) write(cat::perforated_plate(g));
    for (int g : cat::kArchGenera) write(cat::arched_block(g));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tightex_make_genus: %s\n", e.what());
    return 1;
  }
  return 0;
}
