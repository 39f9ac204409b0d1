#include "run/option_help.hpp"

#include <array>
#include <string>

#include "core/error.hpp"

namespace tightex {

namespace {

constexpr std::array kHelps{
    OptionHelp{"size", "--size",
               "texture side in texels (per-component: of the largest component); above 16384 needs --force. Default: the side "
               "that holds as many texels as the input uses (per-component: all the textures together; grown if the atlas cannot "
               "hold a 4x4 rectangle per component; see --texels)"},
    OptionHelp{"texels", "--texels",
               "texel budget: the texture holds this many texels: the smallest square (side a multiple of 4), or as many in the "
               "shape --aspect gives or chooses (per-component: the largest component's texture). Default: the input's used "
               "texels, so the output keeps the input's information"},
    OptionHelp{"map", "--map",
               "detail (default): texels where the input texture has detail (colour gradient per 3D length), capped at 4x the "
               "input's own density; area: the same texels per unit of 3D area everywhere; texel: the input's own texel density "
               "per triangle; harmonic: the paper's map exactly (docs/maps.md)"},
    OptionHelp{"aspect", "--aspect",
               "width/height of the texture, which holds as many texels as a square would: auto (default, area/texel/detail maps): "
               "the component holding most of the texture is mapped at 1:1 and, where its texels are stretched, at the 2:1 or 1:2 "
               "the stretch points to, and the shape whose texels keep the most of the input is chosen (the square unless the "
               "other is clearly better); a number (e.g. 2) fixes it. With --size the default is 1, a square of that side"},
    OptionHelp{"max_page_side", "--max-size",
               "atlas: the largest side of a texture page (default 8192, what WebGL and most engines accept; Cesium ion's cap is "
               "16384; 0: no cap). A budget that does not fit one page goes on several, each component whole on one page; a "
               "component too large for a page is split into pieces that fit, each its own chart (report: \"pages\")"},
    OptionHelp{"max_piece_faces", "--max-piece-faces",
               "the most triangles one chart holds (default 6000000; 0: no cap). A larger component is split into pieces, each "
               "its own chart, so that the map's memory stays about proportional to the triangles (a 10M-face component in one "
               "chart needs about 18 GiB, in two about 12)"},
    OptionHelp{"balance", "--balance",
               "area/texel/detail maps: 1 = target density exactly, 0 = the harmonic map's density (least angle distortion); "
               "between: a geometric blend"},
    OptionHelp{"corners", "--corners",
               "which boundary points become the square's corners: arcs (default): four arcs of equal length; turning: where the "
               "boundary turns most (docs/corners.md)"},
    OptionHelp{"fit", "--no-fit",
               "the least-squares fit of the baked texels to the input under bilinear read-back (--no-fit: each texel by "
               "sampling only)"},
    OptionHelp{"fine_fit", "--fine-fit",
               "fit on 4x4 points per texel instead of 2x2: a little higher surface PSNR, about twice the bake time"},
    OptionHelp{"material_map_budget_db", "--material-map-budget",
               "material maps (a material's textures other than the base colour: metallic-roughness, occlusion, emissive, "
               "normal, specular, ...): a material map one of whose texture slots (each over the channels it reads) is below "
               "this many surface-PSNR dB against the input's at the base colour's size may be baked larger, up to as many "
               "texels as its input image has, while a slot falls short of what the material-map check asks (the base colour's "
               "PSNR plus an ideal re-sampler's difference, at most this) and each step pays for its texels (removes as much "
               "error per added texel as the base colour's texels do); any other material map is halved (down to 1/16 of the base colour's "
               "side) while each slot stays within 0.25 dB of "
               "its figure at the base colour's size, however high (a "
               "normal map: against itself at full size, never larger); default 51; 0 keeps every material map at the base "
               "colour's size. (\"Map\" alone, as in --map, is the parameterization.)"},
    OptionHelp{"allow_large_textures", "--force", "allow a texture side above 16384 (the tile runner's is --allow-large-size)"},
    OptionHelp{"allow_outside_files", "--allow-outside-files",
               "read files the model names (material libraries, textures, glTF buffers and images) outside the folder of the "
               "file that names them: absolute paths, file: URIs, '..' or symbolic links leading out (default: refused, since "
               "a model from elsewhere could pull any readable file into its output)"},
    OptionHelp{"max_memory_mib", "--max-memory", "refuse inputs whose estimated memory exceeds this many MiB (default: 90% of RAM)"},
    OptionHelp{"layout", "--layout", "atlas: all components in one texture; per-component: one texture each (the paper's)"},
    OptionHelp{"texture_format", "--format",
               "texture file format: png, jpg or webp. Default: the input's base colour's (PNG for vertex colours or mixed "
               "inputs); a lossy one at the highest quality whose images take no more bytes than the input's"},
    OptionHelp{"png_level", "--png-level",
               "PNG textures: zlib level 0..9 with the adaptive row filter, or fast (-1 in Options: level 1, run-length "
               "matches, the Up filter; files about a tenth larger, written several times faster). Default 6, zlib's own (9: about 2% "
               "smaller, about 5x the time)"},
    OptionHelp{"jpeg_quality", "--jpeg-quality", "JPEG textures: quality 1..100 (default: rate control, see --format)"},
    OptionHelp{"webp_quality", "--webp-quality", "lossy WebP textures: quality 1..100 (default: rate control, see --format)"},
    OptionHelp{"webp_lossless", "--webp-lossless", "WebP textures: lossless (with --format webp)"},
    OptionHelp{"target_psnr_db", "--target-psnr",
               "lossy textures: the fewest bytes whose written images reach this surface PSNR against the input (dB): the "
               "quality and, without --size or --texels, the texels (and, without --format, the codec)"},
    OptionHelp{"max_bytes", "--max-bytes",
               "lossy textures: the most surface PSNR whose images take at most this many bytes: the quality and, without --size or "
               "--texels, the texels (and, without --format, the codec)"},
    OptionHelp{"compare_reencode", "--compare-reencode",
               "lossy textures: also measure what the input's own images take re-encoded in the output's codec (no repacking, "
               "as gltf-transform or gltfpack would) at the surface PSNR the output's images reach, into the report "
               "(bytes.reencode): what tightex saves. Costs 3 to 7 encodes of the input's images"},
    OptionHelp{"model_format", "--output-format",
               "model file format: obj (OBJ + MTL), ply (binary PLY, textures named by comment TextureFile), gltf (.gltf + .bin "
               "+ texture files) or glb. Default: the input's kind (.ply, .gltf or .glb as the input, anything else .obj)"},
    OptionHelp{"holes", "--holes", "fill: cap holes with scaffolding (paper §4.1); cut: open them into the seam"},
    OptionHelp{"report_path", "--report", "where to write the JSON report (default OUTDIR/report.json)"},
    OptionHelp{"preview_path", "--preview", "write a PNG of the input texture(s) beside the output texture"},
    OptionHelp{"html", "--no-html",
               "write OUTDIR/report.html: the figures, atlases, components and a 3D before/after viewer in one self-contained "
               "page (--no-html: not)"},
    OptionHelp{"keep_untextured", "",
               "triangles with nothing to bake (no texture, no vertex colours) are written as they came; false: their colour is "
               "baked like any other (PLY output always bakes it)"},
    OptionHelp{"measure", "", "compute the docs/metrics.md figures into the report (optimize; a run from a file always measures)"},
};

}  // namespace

std::span<const OptionHelp> option_helps() { return kHelps; }

std::string_view option_help(std::string_view field) {
  for (const OptionHelp& h : kHelps)
    if (h.field == field) return h.help;
  throw InternalError("option_help: no description for " + std::string(field));
}

}  // namespace tightex
