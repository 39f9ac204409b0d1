// report.html: one self-contained page that shows a run (the figures of report.json, the atlases before
// and after, the density, the components, and both models in a 3D viewer). The page's template, style
// and script live in src/report/html/ and, with the three.js they use (Debian's libjs-three), are
// embedded in the binary at build time; everything the page shows is packed into it (base64 arrays,
// data-URI images, downscaled), so it opens from the file system, offline, and fetches nothing; the
// full-size texture files beside it are linked, for a reader to open.
#pragma once
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/mesh.hpp"
#include "report/welded_edges.hpp"

namespace tightex {

/// How much of the models the page holds: together with three.js (about 0.9 MB) the page stays under
/// 3 MB whatever the model.
struct HtmlReportOptions {
  /// Triangles of each model in the 3D viewer at most: above it, both models decimated on one grid
  /// (clustered_mesh: the same surface in both, each with its own texture coordinates and seams); the
  /// page says how many it shows.
  size_t max_triangles = 8000;
  /// Texture images are box-filtered down to at most this many pixels on their longer side, and further
  /// until each model's images take at most max_image_bytes as JPEG; the full-size files are linked.
  int max_texture_side = 1024;
  size_t max_image_bytes = 300000;
  int jpeg_quality = 80;
  /// Per texture of each model, the path of its full-size image relative to the page ("" for none: an
  /// image inside a GLB, a texture made in memory), which the page links.
  std::vector<std::string> input_links, output_links;
};

/// What the page shows of the two models, as JSON text: per model its triangle count, chart count, the
/// shown triangles' positions, indices, texture coordinates, texture index, seam edges and log2 texel
/// density relative to the model's mean (base64 of little-endian typed arrays), and its textures as
/// data-URI JPEGs with their full sizes and the links to their full-size files. Requires two valid meshes (as read_model returns them) with
/// their pixels; `output` is `input` re-textured. Throws only std::bad_alloc.
std::string html_model_data(const TexturedMesh& input, const TexturedMesh& output, const HtmlReportOptions& options = {});

/// html_model_data in two steps, for a caller that counts the charts anyway (measure does): the data
/// without the chart counts, from both models' welded edges (welded_edges, which measure shares), then
/// the text with them.
nlohmann::json html_model_data_without_charts(const TexturedMesh& input, const TexturedMesh& output, const WeldedEdges& input_edges,
                                              const WeldedEdges& output_edges, const HtmlReportOptions& options = {});
std::string html_model_data(nlohmann::json data, size_t input_charts, size_t output_charts);

/// The page: the embedded template with its style, three.js and script, `report_json` (report.json's
/// text) and `model_data` (html_model_data's text) packed in. Never throws but for allocation.
std::string html_report_page(const std::string& report_json, const std::string& model_data);

}  // namespace tightex
