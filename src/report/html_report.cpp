#include "report/html_report.hpp"

#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <string_view>
#include <tuple>
#include <vector>

#include "core/error.hpp"
#include "io/image_io.hpp"
#include "report/metrics.hpp"
#include "report/preview.hpp"
#include "report/view_mesh.hpp"

namespace tightex {

namespace page_assets {
// Defined in the source cmake/embed_files.cmake generates from src/report/html/ and libjs-three.
std::string_view page_html();
std::string_view page_css();
std::string_view page_js();
std::string_view three_js();
std::string_view orbit_controls_js();
}  // namespace page_assets

namespace {

using nlohmann::json;

/// Standard base64 (RFC 4648, with padding) of `size` bytes.
std::string base64(const void* data, size_t size) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* bytes = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (size_t i = 0; i < size; i += 3) {
    const uint32_t b0 = bytes[i], b1 = i + 1 < size ? bytes[i + 1] : 0, b2 = i + 2 < size ? bytes[i + 2] : 0;
    const uint32_t word = (b0 << 16) | (b1 << 8) | b2;
    out += kDigits[(word >> 18) & 63];
    out += kDigits[(word >> 12) & 63];
    out += i + 1 < size ? kDigits[(word >> 6) & 63] : '=';
    out += i + 2 < size ? kDigits[word & 63] : '=';
  }
  return out;
}

/// A typed array's bytes as base64 (the page reads them back as the same little-endian type).
template <typename T>
std::string base64_array(const std::vector<T>& values) {
  static_assert(std::endian::native == std::endian::little, "the page reads little-endian arrays");
  return base64(values.data(), values.size() * sizeof(T));
}

/// Per triangle, bit k set where edge k (corner k to corner k+1) is a seam as docs/metrics.md counts charts:
/// the texture coordinates (or the texture) differ on its two sides, or it has not exactly one
/// neighbour across it (a border, or a non-manifold edge).
std::vector<uint8_t> seam_bits(const TexturedMesh& mesh, const WeldedEdges& edges) {
  std::vector<uint8_t> bits(mesh.num_triangles(), 0);
  // The texture coordinate of half-edge h's triangle at welded vertex v (one of the edge's two ends).
  auto uv_at = [&](uint32_t h, uint32_t v) {
    const size_t t = h / 3;
    const int k = int(h % 3);
    return edges.end_of(mesh, h, 0) == v ? mesh.corner_uv[3 * t + k] : mesh.corner_uv[3 * t + (k + 1) % 3];
  };
  edges.for_each_edge(mesh, [&](size_t i, size_t j) {
    bool seam = j - i != 2;
    if (!seam) {
      const uint32_t h0 = edges.by_ends[i], h1 = edges.by_ends[i + 1];
      const uint32_t a = edges.lower(mesh, h0), b = edges.higher(mesh, h0);
      seam = texture_of(mesh, h0 / 3) != texture_of(mesh, h1 / 3) || uv_at(h0, a) != uv_at(h1, a) || uv_at(h0, b) != uv_at(h1, b);
    }
    if (seam)
      for (size_t e = i; e < j; ++e) bits[edges.by_ends[e] / 3] |= uint8_t(1u << (edges.by_ends[e] % 3));
  });
  return bits;
}

/// Per triangle, log2 of its texel density (texels of its texture per unit of 3D area) over the
/// model's mean density (all texels over all area), as docs/metrics.md's density spread; NaN for a triangle
/// without texture or area.
std::vector<double> relative_density(const TexturedMesh& mesh) {
  std::vector<double> density(mesh.num_triangles(), std::numeric_limits<double>::quiet_NaN());
  double texels = 0, area = 0;
  for (size_t t = 0; t < mesh.num_triangles(); ++t) {
    const int tex = texture_of(mesh, t);
    const Vec3 &p0 = mesh.positions[mesh.triangles[t][0]], &p1 = mesh.positions[mesh.triangles[t][1]],
               &p2 = mesh.positions[mesh.triangles[t][2]];
    const double a3 = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    if (tex < 0 || !(a3 > 0)) continue;
    const auto [w, h] = texture_size(mesh, tex);
    const Vec2 e1 = mesh.sampled_uv(t, 1) - mesh.sampled_uv(t, 0), e2 = mesh.sampled_uv(t, 2) - mesh.sampled_uv(t, 0);
    const double at = 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x()) * double(w) * double(h);
    density[t] = at / a3;
    texels += at, area += a3;
  }
  const double mean = area > 0 && texels > 0 ? texels / area : 1;
  for (double& d : density)
    if (!std::isnan(d)) d = d > 0 ? std::log2(d / mean) : -60.0;
  return density;
}

/// The map slots texture i serves besides a base colour ("metallic_roughness + occlusion"), or "" for a
/// base colour or a texture no material binds as a map.
std::string map_slots_of(const TexturedMesh& mesh, int i) {
  std::string slots;
  for (const Material& m : mesh.materials)
    if (m.texture == i) return "";
  for (size_t s = 0; s < kMaterialSlots; ++s) {
    const bool bound = std::any_of(mesh.materials.begin(), mesh.materials.end(), [&](const Material& m) { return m.maps[s] == i; });
    if (bound) slots += (slots.empty() ? "" : " + ") + std::string(material_slot_name(MaterialSlot(s)));
  }
  return slots;
}

/// The model's textures as data-URI JPEGs box-filtered to at most `side` pixels on their longer side
/// ("" where the pixels are not loaded).
std::vector<std::string> texture_uris(const TexturedMesh& mesh, int side, int quality) {
  std::vector<std::string> uris;
  for (const Texture& texture : mesh.textures) {
    const Image& image = texture.image;
    if (image.empty()) {
      uris.emplace_back();
      continue;
    }
    const int longer = std::max(image.width, image.height);
    const int height = longer > side ? std::max(1, int(std::lround(double(image.height) * side / longer))) : image.height;
    const std::string jpeg = encode_jpeg(height == image.height ? image : box_shrink(image, height), quality);
    uris.push_back("data:image/jpeg;base64," + base64(jpeg.data(), jpeg.size()));
  }
  return uris;
}

/// The model's textures for display: full size, the image downscaled until all of them fit
/// HtmlReportOptions::max_image_bytes (texture_uris), the file of the full-size image (`links`, "" for
/// none) and the map slots each serves ("map": "" for a base colour).
json textures_json(const TexturedMesh& mesh, const HtmlReportOptions& options, const std::vector<std::string>& links) {
  // A first side from the budget shared by the pages, then smaller until the images fit.
  const double pages = double(std::max<size_t>(mesh.textures.size(), 1));
  int side = std::min(options.max_texture_side, std::max(16, int(std::sqrt(double(options.max_image_bytes) * 5 / pages))));
  std::vector<std::string> uris;
  for (;;) {
    uris = texture_uris(mesh, side, options.jpeg_quality);
    size_t bytes = 0;
    for (const std::string& u : uris) bytes += u.size();
    if (bytes <= options.max_image_bytes * 4 / 3 || side <= 16) break;
    side = std::max(16, int(side * 0.75));
  }
  json textures = json::array();
  for (size_t i = 0; i < mesh.textures.size(); ++i) {
    const auto [w, h] = texture_size(mesh, int(i));
    textures.push_back({{"width", w},
                        {"height", h},
                        {"image", uris[i]},
                        {"file", i < links.size() ? links[i] : std::string()},
                        {"map", map_slots_of(mesh, int(i))}});
  }
  return textures;
}

/// One model's entry of html_model_data: `view` (the model, or a decimated copy: clustered_mesh) with
/// its welded edges for the 3D views, `mesh`'s own counts and textures.
json model_json(const TexturedMesh& mesh, const TexturedMesh& view, const WeldedEdges& edges, const std::string& name,
                const HtmlReportOptions& options, const std::vector<std::string>& links) {
  const std::vector<uint8_t> seams = seam_bits(view, edges);
  const std::vector<double> all_density = relative_density(view);
  std::vector<uint32_t> indices;
  std::vector<float> positions, uv, density;
  std::vector<int16_t> texture;
  for (const Vec3& p : view.positions) positions.insert(positions.end(), {float(p.x()), float(p.y()), float(p.z())});
  for (size_t t = 0; t < view.num_triangles(); ++t) {
    for (int k = 0; k < 3; ++k) {
      indices.push_back(view.triangles[t][k]);
      const Vec2 c = view.sampled_uv(t, k);
      uv.insert(uv.end(), {float(c.x()), float(c.y())});
    }
    texture.push_back(int16_t(std::clamp(texture_of(view, t), -1, int(INT16_MAX))));
    density.push_back(float(all_density[t]));
  }
  return {{"name", name},
          {"triangles", mesh.num_triangles()},
          {"shown", view.num_triangles()},
          {"positions", base64_array(positions)},
          {"indices", base64_array(indices)},
          {"uv", base64_array(uv)},
          {"texture", base64_array(texture)},
          {"seams", base64_array(seams)},
          {"density", base64_array(density)},
          {"textures", textures_json(mesh, options, links)}};
}

/// `text` with every "<" written as the JSON escape "\u003c", so that no "</script>" in a string can
/// end the script element that holds it (and the JSON means the same).
std::string escape_for_script(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text)
    if (c == '<')
      out += "\\u003c";
    else
      out += c;
  return out;
}

/// One marker of the template and what replaces it.
struct Filling {
  std::string_view marker, content;
};

/// `page` with each marker replaced by its content. The markers are all found in the template itself
/// (never inside a content: a file name in the report could spell one). A marker the template lacks,
/// or holds twice, is a broken build (InternalError).
std::string filled(std::string_view page, std::vector<Filling> fillings) {
  std::vector<std::pair<size_t, const Filling*>> at;
  for (const Filling& f : fillings) {
    const size_t pos = page.find(f.marker);
    if (pos == std::string_view::npos || page.find(f.marker, pos + 1) != std::string_view::npos)
      throw InternalError("report.html template: not exactly one " + std::string(f.marker));
    at.push_back({pos, &f});
  }
  std::sort(at.begin(), at.end());
  std::string out;
  size_t from = 0;
  for (const auto& [pos, f] : at) {
    out.append(page.substr(from, pos - from));
    out.append(f->content);
    from = pos + f->marker.size();
  }
  out.append(page.substr(from));
  return out;
}

}  // namespace

std::string html_model_data(const TexturedMesh& input, const TexturedMesh& output, const HtmlReportOptions& options) {
  WeldedEdges input_edges, output_edges;
  tbb::parallel_invoke([&] { input_edges = welded_edges(input); }, [&] { output_edges = welded_edges(output); });
  size_t input_charts = 0, output_charts = 0;
  json data;
  tbb::parallel_invoke([&] { data = html_model_data_without_charts(input, output, input_edges, output_edges, options); },
                       [&] { input_charts = count_charts(input, input_edges, nullptr); },
                       [&] { output_charts = count_charts(output, output_edges, nullptr); });
  return html_model_data(std::move(data), input_charts, output_charts);
}

std::string html_model_data(json data, size_t input_charts, size_t output_charts) {
  data["models"][0]["charts"] = input_charts;
  data["models"][1]["charts"] = output_charts;
  return data.dump();
}

json html_model_data_without_charts(const TexturedMesh& input, const TexturedMesh& output, const WeldedEdges& input_edges,
                                    const WeldedEdges& output_edges, const HtmlReportOptions& options) {
  // One grid for both, from the input, so that both views show the same decimated surface; grown
  // where the output (the same surface, cut otherwise) would keep more triangles than the cap.
  double cell = cluster_cell(input, options.max_triangles);
  TexturedMesh in_view, out_view;
  WeldedEdges in_view_edges, out_view_edges;
  while (cell > 0) {
    in_view = clustered_mesh(input, cell);  // one after the other: each holds arrays per corner meanwhile
    out_view = clustered_mesh(output, cell);
    if (out_view.num_triangles() <= options.max_triangles) break;
    cell *= 1.15;
  }
  if (cell > 0) tbb::parallel_invoke([&] { in_view_edges = welded_edges(in_view); }, [&] { out_view_edges = welded_edges(out_view); });
  json in, out;  // side by side: each encodes its own textures
  tbb::parallel_invoke(
      [&] {
        in = model_json(input, cell > 0 ? in_view : input, cell > 0 ? in_view_edges : input_edges, "input", options, options.input_links);
      },
      [&] {
        out = model_json(output, cell > 0 ? out_view : output, cell > 0 ? out_view_edges : output_edges, "output", options,
                         options.output_links);
      });
  return {{"max_triangles", options.max_triangles}, {"models", json::array({std::move(in), std::move(out)})}};
}

std::string html_report_page(const std::string& report_json, const std::string& model_data) {
  const std::string report = escape_for_script(report_json), models = escape_for_script(model_data);
  return filled(page_assets::page_html(), {{"/*TIGHTEX:STYLE*/", page_assets::page_css()},
                                           {"TIGHTEX:REPORT_JSON", report},
                                           {"TIGHTEX:MODEL_DATA", models},
                                           {"/*TIGHTEX:THREE*/", page_assets::three_js()},
                                           {"/*TIGHTEX:ORBIT_CONTROLS*/", page_assets::orbit_controls_js()},
                                           {"/*TIGHTEX:SCRIPT*/", page_assets::page_js()}});
}

}  // namespace tightex
