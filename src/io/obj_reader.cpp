// Wavefront OBJ + MTL reader. The whole file is read into memory and scanned once, line by line, with
// std::from_chars for numbers, and every problem is reported as "FILE:LINE: problem" on one line.
//
// Things that cannot be checked while scanning (positive indices that point forward, usemtl before
// its mtllib, faces without texture coordinates) are recorded with their line and checked once the
// whole file is read, so the error still names the line that caused it.
#include "io/obj_reader.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "io/image_io.hpp"
#include "io/model_files.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;

// Beyond this a coordinate is an exporter bug (uninitialised memory, a unit mistake of many orders of
// magnitude), and squaring it in any later area or length computation would overflow or lose all
// precision.
constexpr double kAbsurdCoordinate = 1e15;

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

[[noreturn]] void fail_at_line(const std::string& file, size_t line, const std::string& problem) {
  fail_input("{}:{}: {}", file, line, problem);
}

template <typename T>
void reserve_prefaulted(std::vector<T>& v, size_t n) {
  v.reserve(n);
  prefault_for_write(v.data(), n * sizeof(T));
}

/// How many statements of each kind a file holds, counted in a quick first pass so the arrays are
/// allocated once at their final size instead of growing (and copying) as they fill.
struct StatementCounts {
  size_t v = 0, vt = 0, vn = 0, f = 0;
};

StatementCounts count_statements(std::string_view text) {
  StatementCounts counts;
  const char* p = text.data();
  const char* const end = p + text.size();
  while (p < end) {
    while (p < end && (*p == ' ' || *p == '\t')) ++p;
    if (end - p >= 2) {
      const bool blank_after_1 = is_blank(p[1]);
      const bool blank_after_2 = end - p >= 3 && is_blank(p[2]);
      if (p[0] == 'v') {
        if (blank_after_1)
          ++counts.v;
        else if (p[1] == 't' && blank_after_2)
          ++counts.vt;
        else if (p[1] == 'n' && blank_after_2)
          ++counts.vn;
      } else if (p[0] == 'f' && blank_after_1) {
        ++counts.f;
      }
    }
    const auto* nl = static_cast<const char*>(std::memchr(p, '\n', size_t(end - p)));
    p = nl != nullptr ? nl + 1 : end;
  }
  return counts;
}

/// Splits a buffer into lines; the last line need not end with '\n'. '\r' is left for the
/// tokenizer, which treats it as blank, so CRLF files need no special case.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : p_(text.data()), end_(text.data() + text.size()) {}

  bool next(std::string_view& line) {
    if (p_ >= end_) return false;
    const auto* nl = static_cast<const char*>(std::memchr(p_, '\n', size_t(end_ - p_)));
    const char* line_end = nl != nullptr ? nl : end_;
    line = std::string_view(p_, size_t(line_end - p_));
    p_ = nl != nullptr ? nl + 1 : end_;
    ++number_;
    return true;
  }
  size_t number() const { return number_; }

 private:
  const char* p_;
  const char* end_;
  size_t number_ = 0;
};

/// Whitespace-separated tokens of one line. A token starting with '#' ends the line: exporters
/// append comments to data lines, and '#' is never part of a number or a face corner.
class Tokens {
 public:
  explicit Tokens(std::string_view line) : p_(line.data()), end_(line.data() + line.size()) {}

  std::string_view next() {
    while (p_ < end_ && is_blank(*p_)) ++p_;
    if (p_ == end_ || *p_ == '#') {
      p_ = end_;
      return {};
    }
    const char* start = p_;
    while (p_ < end_ && !is_blank(*p_)) ++p_;
    return {start, size_t(p_ - start)};
  }
  std::string_view peek() {
    const char* saved = p_;
    const std::string_view t = next();
    p_ = saved;
    return t;
  }
  /// The rest of the line verbatim (minus surrounding blanks): file and material names may contain
  /// spaces and '#'.
  std::string_view rest() {
    const std::string_view r = trim(std::string_view(p_, size_t(end_ - p_)));
    p_ = end_;
    return r;
  }

 private:
  const char* p_;
  const char* end_;
};

enum class IndexKind : uint8_t { kVertex, kTexcoord, kNormal };

const char* kind_name(IndexKind k) {
  switch (k) {
    case IndexKind::kVertex:
      return "vertex";
    case IndexKind::kTexcoord:
      return "texture coordinate";
    case IndexKind::kNormal:
      return "normal";
  }
  return "?";
}

const char* kind_plural(IndexKind k) {
  switch (k) {
    case IndexKind::kVertex:
      return "vertices";
    case IndexKind::kTexcoord:
      return "texture coordinates";
    case IndexKind::kNormal:
      return "normals";
  }
  return "?";
}

/// A positive index beyond what was defined at its line: legal only if the element is defined
/// later, which is checked when the whole file has been read.
struct ForwardRef {
  size_t line;
  int64_t index;  // as written (1-based)
  IndexKind kind;
};

/// A material as defined in an MTL file, with what is needed to load and blame its texture.
struct MaterialDef {
  Material material;
  std::string mtl_path;          // for messages
  std::string texture_written;   // map_Kd file name as written; empty: no texture
  std::string texture_resolved;  // resolved against the MTL's folder
  size_t texture_line = 0;
  /// The other maps (MapSlot: map_Ks, map_Ke, map_Pr, map_Pm, norm, map_Bump / bump), as map_Kd's.
  std::array<std::string, kMapSlots> map_written, map_resolved;
  std::array<size_t, kMapSlots> map_line{};
};

/// The MapSlot an MTL keyword binds (matched without case), or -1: map_Ks specular colour, map_Ke
/// emissive, map_Pr roughness, map_Pm metallic, norm a tangent-space normal map, map_Bump / bump a
/// height map.
int mtl_map_slot(std::string_view keyword) {
  static constexpr std::pair<const char*, MapSlot> kKeywords[] = {
      {"map_Ks", MapSlot::kSpecular}, {"map_Ke", MapSlot::kEmissive}, {"map_Pr", MapSlot::kRoughness}, {"map_Pm", MapSlot::kMetallic},
      {"norm", MapSlot::kNormal},     {"map_Bump", MapSlot::kBump},   {"bump", MapSlot::kBump}};
  for (const auto& [word, slot] : kKeywords)
    if (equals_ignoring_case(keyword, word)) return int(slot);
  return -1;
}

/// Skips a map statement's options (each "-name" and the values after it: numbers, on/off, or
/// -imfchan's channel), leaving the file name. The maps other than map_Kd are read at map_Kd's
/// coordinates; their own -s/-o are not applied.
void skip_map_options(Tokens& tokens) {
  while (!tokens.peek().empty() && tokens.peek()[0] == '-') {
    const std::string_view opt = tokens.next();
    if (opt == "-imfchan") {
      tokens.next();
      continue;
    }
    double value = 0;
    while (!tokens.peek().empty() && (parse_double(tokens.peek(), value) || tokens.peek() == "on" || tokens.peek() == "off")) tokens.next();
  }
}

/// A material name given to usemtl, resolved once every mtllib has been read.
struct MaterialUse {
  std::string name;
  size_t first_line;
};

struct Corner {
  uint32_t v = kNone, vt = kNone, vn = kNone;
};

/// Reads map_Kd's options, which come before the file name (each takes a fixed or bounded number of
/// arguments): -s and -o into `scale` and `offset`, the others checked and skipped.
void read_map_kd_options(Tokens& tokens, const std::string& mtl_name, size_t mtl_line, std::array<double, 3>& scale,
                         std::array<double, 3>& offset) {
  for (std::string_view opt = tokens.peek(); opt.size() > 1 && opt[0] == '-'; opt = tokens.peek()) {
    tokens.next();
    const std::string_view name = opt.substr(1);
    auto numbers = [&](size_t min_count, size_t max_count, double* out) {
      size_t n = 0;
      while (n < max_count) {
        const std::string_view t = tokens.peek();
        double value = 0.0;
        const bool ok = !t.empty() && parse_double(t, value);
        if (!ok) {
          if (n < min_count)
            fail_at_line(mtl_name, mtl_line,
                         t.empty() ? fmt::format("option '{}' of 'map_Kd' needs {} value(s)", opt, min_count)
                                   : fmt::format("malformed number '{}' for option '{}' of 'map_Kd'", excerpt(t), opt));
          break;
        }
        if (!std::isfinite(value)) fail_at_line(mtl_name, mtl_line, fmt::format("NaN or infinite value for option '{}' of 'map_Kd'", opt));
        tokens.next();
        if (out != nullptr) out[n] = value;
        ++n;
      }
    };
    if (name == "s") {
      numbers(1, 3, scale.data());
    } else if (name == "o") {
      numbers(1, 3, offset.data());
    } else if (name == "t") {
      numbers(1, 3, nullptr);
    } else if (name == "mm") {
      numbers(2, 2, nullptr);
    } else if (name == "bm" || name == "boost" || name == "texres") {
      numbers(1, 1, nullptr);
    } else if (name == "blendu" || name == "blendv" || name == "clamp" || name == "cc") {
      const std::string_view v = tokens.next();
      if (v != "on" && v != "off")
        fail_at_line(mtl_name, mtl_line, fmt::format("option '{}' of 'map_Kd' needs on or off, got '{}'", opt, excerpt(v)));
    } else if (name == "imfchan") {
      if (tokens.next().empty()) fail_at_line(mtl_name, mtl_line, "option '-imfchan' of 'map_Kd' needs a channel");
    } else {
      fail_at_line(mtl_name, mtl_line, fmt::format("unknown option '{}' in 'map_Kd'", excerpt(opt)));
    }
  }
}

class ObjParser {
 public:
  ObjParser(const std::string& path, const ObjReadOptions& options) : path_(path), options_(options) {}

  TexturedMesh read(ObjReadStats* stats);

 private:
  template <typename... Args>
  [[noreturn]] void fail_here(fmt::format_string<Args...> f, Args&&... args) const {
    fail_input("{}:{}: {}", path_, line_, fmt::format(f, std::forward<Args>(args)...));
  }

  void parse_line(std::string_view line);
  void parse_vertex(Tokens& tokens);
  void add_vertex_colour(const double* values, size_t n);
  void parse_texcoord(Tokens& tokens);
  void parse_normal(Tokens& tokens);
  void parse_face(Tokens& tokens);
  void parse_corner(std::string_view token, Corner& corner, bool& has_vt, bool& has_vn);
  uint32_t resolve_index(std::string_view text, IndexKind kind, std::string_view token);
  void parse_mtllib(std::string_view rest);
  void parse_usemtl(std::string_view rest);
  void load_mtl(const fs::path& mtl_path, const std::string& data);

  size_t parse_numbers(Tokens& tokens, std::string_view keyword, double* out, size_t max_count);
  void check_coordinate(double value, std::string_view what) const;

  void check_forward_refs() const;
  bool coloured() const;
  void check_texture_coordinates() const;
  void assemble_uvs(TexturedMesh& mesh) const;
  void assemble_colours(TexturedMesh& mesh) const;
  void assemble_materials(TexturedMesh& mesh);

  const std::string& path_;
  const ObjReadOptions& options_;
  size_t line_ = 0;

  std::vector<Vec3> positions_;
  std::vector<Vec2> texcoords_;
  std::vector<Vec3> normals_;
  std::vector<std::array<float, 4>> vertex_colours_;  // per vertex while every vertex so far has r g b
  bool all_vertices_coloured_ = true;
  bool colours_above_one_ = false;  // then the file writes colours as 0..255
  std::vector<Tri> triangles_;
  std::vector<uint32_t> corner_vt_;    // 3 per triangle
  std::vector<uint32_t> corner_vn_;    // 3 per triangle while every face so far has normals
  std::vector<int32_t> triangle_use_;  // index into uses_, -1 before any usemtl
  std::vector<Corner> face_corners_;   // scratch for the face being parsed
  std::vector<ForwardRef> forward_refs_;

  bool all_faces_have_normals_ = true;
  bool normals_finite_ = true;
  size_t first_face_without_vt_ = 0;  // line, 0 = none
  size_t polygons_triangulated_ = 0;
  // Statements tightex does not know (curves, surfaces, vp, ...); counted, not fatal. ObjReadStats
  // has no field for this yet.
  size_t unknown_statements_ = 0;

  int32_t current_use_ = -1;
  std::vector<MaterialUse> uses_;
  std::unordered_map<std::string, int32_t> use_by_name_;

  std::vector<MaterialDef> defs_;
  std::unordered_map<std::string, size_t> def_by_name_;  // first definition of a name wins
  std::vector<std::string> loaded_mtls_;                 // each library is read once
  std::vector<std::string> paths_found_;                 // ObjReadStats::paths_found
  std::vector<std::string> not_read_;                    // ObjReadStats::not_read: maps whose file is missing
  /// find_named_file, noting in paths_found_ a file found under another name than written.
  std::optional<fs::path> locate(const fs::path& folder, const std::string& written) {
    std::optional<fs::path> found = find_named_file(folder, written);
    if (found && *found != folder / written) paths_found_.push_back(fmt::format("{} -> {}", written, found->lexically_normal().string()));
    return found;
  }
  bool saw_mtllib_ = false;
};

TexturedMesh ObjParser::read(ObjReadStats* stats) {
  std::string data;
  std::string reason;
  if (!read_whole_file(path_, data, reason)) fail_input("{}: {}", path_, reason);
  // A binary file (a PNG or a PLY picked by mistake) would otherwise "parse" as unknown statements
  // and end in a puzzling "no faces".
  if (std::memchr(data.data(), '\0', data.size()) != nullptr)
    fail_input("{}: not a text file (contains NUL bytes); expected a Wavefront OBJ", path_);

  const StatementCounts counts = count_statements(data);
  reserve_prefaulted(positions_, counts.v);
  reserve_prefaulted(texcoords_, counts.vt);
  reserve_prefaulted(normals_, counts.vn);
  // One triangle per face is exact for the triangle meshes scanners write; polygons grow the arrays.
  reserve_prefaulted(triangles_, counts.f);
  reserve_prefaulted(corner_vt_, 3 * counts.f);
  if (counts.vn > 0) reserve_prefaulted(corner_vn_, 3 * counts.f);
  reserve_prefaulted(triangle_use_, counts.f);

  LineReader lines(data);
  std::string_view line;
  while (lines.next(line)) {
    line_ = lines.number();
    parse_line(line);
  }
  line_ = 0;

  if (triangles_.empty()) fail_input("{}: no faces", path_);
  check_forward_refs();
  check_texture_coordinates();

  TexturedMesh mesh;
  mesh.source = path_;
  mesh.positions = std::move(positions_);
  assemble_uvs(mesh);
  assemble_colours(mesh);
  mesh.triangles = std::move(triangles_);
  // Normals are all-or-nothing: a half-filled array would make every consumer check each corner.
  if (all_faces_have_normals_ && normals_finite_ && !normals_.empty()) {
    reserve_prefaulted(mesh.corner_normal, corner_vn_.size());
    mesh.corner_normal.resize(corner_vn_.size());
    for (size_t i = 0; i < corner_vn_.size(); ++i) mesh.corner_normal[i] = normals_[corner_vn_[i]];
  }
  mesh.face_material = std::move(triangle_use_);
  assemble_materials(mesh);

  if (stats != nullptr) {
    stats->polygons_triangulated = polygons_triangulated_;
    stats->lines = lines.number();
    stats->paths_found = paths_found_;
    stats->not_read = not_read_;
  }
  return mesh;
}

bool ObjParser::coloured() const { return all_vertices_coloured_ && !vertex_colours_.empty(); }

/// Every face needs texture coordinates, unless the model is vertex-coloured (every vertex has r g b):
/// then a face without them takes its texture from the colours.
void ObjParser::check_texture_coordinates() const {
  if (coloured()) return;
  if (texcoords_.empty())
    fail_input(
        "{}: model has neither texture coordinates (vt) nor vertex colours (v x y z r g b); tightex needs the input's UV atlas or "
        "its vertex colours",
        path_);
  if (first_face_without_vt_ != 0)
    fail_input("{}:{}: face has no texture coordinates (every face needs v/vt indices)", path_, first_face_without_vt_);
}

/// The corners' texture coordinates; (0, 0) where a vertex-coloured model's face has none.
void ObjParser::assemble_uvs(TexturedMesh& mesh) const {
  reserve_prefaulted(mesh.corner_uv, corner_vt_.size());
  mesh.corner_uv.resize(corner_vt_.size());
  for (size_t i = 0; i < corner_vt_.size(); ++i) mesh.corner_uv[i] = corner_vt_[i] == kNone ? Vec2::Zero() : texcoords_[corner_vt_[i]];
}

/// Per corner, its vertex's colour, in [0, 1]: a file with any value above 1 writes them as 0..255.
void ObjParser::assemble_colours(TexturedMesh& mesh) const {
  if (!coloured()) return;
  const float scale = colours_above_one_ ? 1.0f / 255.0f : 1.0f;
  mesh.corner_color.reserve(3 * triangles_.size());
  for (const Tri& t : triangles_)
    for (const uint32_t v : t) {
      std::array<float, 4> c = vertex_colours_[v];
      for (int k = 0; k < 3; ++k) c[size_t(k)] = std::clamp(c[size_t(k)] * scale, 0.0f, 1.0f);
      mesh.corner_color.push_back(c);
    }
}

void ObjParser::parse_line(std::string_view line) {
  Tokens tokens(line);
  const std::string_view keyword = tokens.next();
  if (keyword.empty()) return;  // blank line or comment
  // Most frequent first: v, vt and f make up nearly every line of a scan.
  if (keyword == "v") return parse_vertex(tokens);
  if (keyword == "vt") return parse_texcoord(tokens);
  if (keyword == "f") return parse_face(tokens);
  if (keyword == "vn") return parse_normal(tokens);
  if (keyword == "usemtl") return parse_usemtl(tokens.rest());
  if (keyword == "mtllib") return parse_mtllib(tokens.rest());
  // Object and group names, smoothing groups, and line and point elements carry nothing a texture
  // needs.
  if (keyword == "o" || keyword == "g" || keyword == "s" || keyword == "l" || keyword == "p") return;
  ++unknown_statements_;
}

/// Parses up to max_count numbers; fails on a malformed one or on more than max_count.
size_t ObjParser::parse_numbers(Tokens& tokens, std::string_view keyword, double* out, size_t max_count) {
  size_t n = 0;
  for (std::string_view t = tokens.next(); !t.empty(); t = tokens.next()) {
    if (n == max_count) fail_here("too many values in '{}' (at most {})", keyword, max_count);
    if (!parse_double(t, out[n])) fail_here("malformed number '{}' in '{}'", excerpt(t), keyword);
    ++n;
  }
  return n;
}

void ObjParser::check_coordinate(double value, std::string_view what) const {
  if (!std::isfinite(value)) fail_here("NaN or infinite {}", what);
  if (std::abs(value) > kAbsurdCoordinate) fail_here("absurd {} {:g} (absolute value above 1e15)", what, value);
}

void ObjParser::parse_vertex(Tokens& tokens) {
  // x y z, then either w or r g b (vertex colours, written by scanners and MeshLab), possibly followed
  // by more numbers, which are checked and ignored.
  double values[7];
  const size_t n = parse_numbers(tokens, "v", values, 7);
  if (n < 3) fail_here("'v' needs 3 coordinates, got {}", n);
  for (size_t i = 0; i < 3; ++i) check_coordinate(values[i], "coordinate");
  if (positions_.size() >= size_t(kNone) - 1) fail_here("too many vertices");
  positions_.emplace_back(values[0], values[1], values[2]);
  add_vertex_colour(values, n);
}

/// `v x y z r g b`: the colour, kept while every vertex so far has one (all-or-nothing, as normals).
void ObjParser::add_vertex_colour(const double* values, size_t n) {
  if (!all_vertices_coloured_) return;
  if (n < 6) {
    all_vertices_coloured_ = false;
    vertex_colours_ = {};
    return;
  }
  std::array<float, 4> c{0.0f, 0.0f, 0.0f, 1.0f};
  for (size_t k = 0; k < 3; ++k) {
    if (!std::isfinite(values[3 + k]) || values[3 + k] < 0)
      fail_here("vertex colour {:g} is not a number from 0 to 1 (or 0 to 255)", values[3 + k]);
    colours_above_one_ = colours_above_one_ || values[3 + k] > 1.0;
    c[k] = float(values[3 + k]);
  }
  vertex_colours_.push_back(c);
}

void ObjParser::parse_texcoord(Tokens& tokens) {
  double values[3] = {0.0, 0.0, 0.0};  // v and w default to 0 (OBJ specification)
  const size_t n = parse_numbers(tokens, "vt", values, 3);
  if (n < 1) fail_here("'vt' needs at least 1 value");
  for (size_t i = 0; i < 2; ++i) check_coordinate(values[i], "texture coordinate");
  if (texcoords_.size() >= size_t(kNone) - 1) fail_here("too many texture coordinates");
  texcoords_.emplace_back(values[0], values[1]);
}

void ObjParser::parse_normal(Tokens& tokens) {
  double values[3];
  const size_t n = parse_numbers(tokens, "vn", values, 3);
  if (n != 3) fail_here("'vn' needs 3 values, got {}", n);
  // Exporters write NaN normals for degenerate faces. Normals are optional, so such a file loses its
  // normals instead of being refused.
  if (!std::isfinite(values[0]) || !std::isfinite(values[1]) || !std::isfinite(values[2])) normals_finite_ = false;
  if (normals_.size() >= size_t(kNone) - 1) fail_here("too many normals");
  normals_.emplace_back(values[0], values[1], values[2]);
}

uint32_t ObjParser::resolve_index(std::string_view text, IndexKind kind, std::string_view token) {
  const char* b = text.data();
  const char* e = b + text.size();
  if (b != e && *b == '+') {
    ++b;
    if (b != e && *b == '-') fail_here("malformed face corner '{}'", excerpt(token));
  }
  int64_t index = 0;
  const auto [ptr, ec] = std::from_chars(b, e, index);
  if (ptr != e || b == e || (ec != std::errc() && ec != std::errc::result_out_of_range))
    fail_here("malformed face corner '{}'", excerpt(token));
  const size_t defined = kind == IndexKind::kVertex     ? positions_.size()
                         : kind == IndexKind::kTexcoord ? texcoords_.size()
                                                        : normals_.size();
  if (ec == std::errc::result_out_of_range)
    fail_here("{} index {} out of range (file has {} {} so far)", kind_name(kind), excerpt(text), defined, kind_plural(kind));
  if (index == 0) fail_here("index 0 is invalid (OBJ indices start at 1)");
  if (index < 0) {
    // Relative: -1 is the latest element defined before this line.
    if (uint64_t(-index) > defined)
      fail_here("{} index {} out of range (only {} {} defined before this line)", kind_name(kind), index, defined, kind_plural(kind));
    return uint32_t(int64_t(defined) + index);
  }
  if (uint64_t(index) > defined) {
    // Maybe defined further down; checked at the end with this line's number.
    if (index >= int64_t(kNone)) fail_here("{} index {} out of range (more than any file can hold)", kind_name(kind), index);
    forward_refs_.push_back({line_, index, kind});
  }
  return uint32_t(index - 1);
}

void ObjParser::parse_corner(std::string_view token, Corner& corner, bool& has_vt, bool& has_vn) {
  // v, v/vt, v/vt/vn or v//vn.
  const size_t slash1 = token.find('/');
  corner.v = resolve_index(token.substr(0, slash1), IndexKind::kVertex, token);
  if (slash1 == std::string_view::npos) {
    has_vt = has_vn = false;
    return;
  }
  const std::string_view after = token.substr(slash1 + 1);
  const size_t slash2 = after.find('/');
  const std::string_view vt_text = after.substr(0, slash2);
  if (vt_text.empty()) {
    // "v/" alone is malformed; "v//vn" has an empty vt on purpose.
    if (slash2 == std::string_view::npos) fail_here("malformed face corner '{}'", excerpt(token));
    has_vt = false;
  } else {
    corner.vt = resolve_index(vt_text, IndexKind::kTexcoord, token);
  }
  if (slash2 == std::string_view::npos) {
    has_vn = false;
    return;
  }
  const std::string_view vn_text = after.substr(slash2 + 1);
  if (vn_text.empty()) fail_here("malformed face corner '{}'", excerpt(token));
  corner.vn = resolve_index(vn_text, IndexKind::kNormal, token);
}

void ObjParser::parse_face(Tokens& tokens) {
  face_corners_.clear();
  bool has_vt = true, has_vn = true;
  for (std::string_view t = tokens.next(); !t.empty(); t = tokens.next()) {
    Corner& c = face_corners_.emplace_back();
    parse_corner(t, c, has_vt, has_vn);
  }
  const size_t n = face_corners_.size();
  if (n < 3) fail_here("face has {} corner{} (needs at least 3)", n, n == 1 ? "" : "s");
  if (!has_vt && first_face_without_vt_ == 0) first_face_without_vt_ = line_;
  if (!has_vn && all_faces_have_normals_) {
    // Normals are all-or-nothing, so the normal indices are of no use from here on.
    all_faces_have_normals_ = false;
    corner_vn_ = {};
  }
  if (n > 3) ++polygons_triangulated_;
  // Fan around the first corner: exact for the convex polygons exporters write, and it keeps the
  // polygon's winding.
  for (size_t i = 1; i + 1 < n; ++i) {
    const Corner& a = face_corners_[0];
    const Corner& b = face_corners_[i];
    const Corner& c = face_corners_[i + 1];
    triangles_.push_back({a.v, b.v, c.v});
    corner_vt_.insert(corner_vt_.end(), {a.vt, b.vt, c.vt});
    if (all_faces_have_normals_) corner_vn_.insert(corner_vn_.end(), {a.vn, b.vn, c.vn});
    triangle_use_.push_back(current_use_);
  }
}

void ObjParser::parse_usemtl(std::string_view rest) {
  if (rest.empty()) fail_here("'usemtl' without a material name");
  const std::string name(rest);
  const auto [it, inserted] = use_by_name_.try_emplace(name, int32_t(uses_.size()));
  if (inserted) uses_.push_back({name, line_});
  current_use_ = it->second;
}

void ObjParser::parse_mtllib(std::string_view rest) {
  if (rest.empty()) fail_here("'mtllib' without a file name");
  saw_mtllib_ = true;
  const fs::path folder = fs::path(path_).parent_path();
  const std::string whole = with_forward_slashes(rest);
  // mtllib may list several files separated by blanks, but a single file name may also contain
  // spaces: the whole rest of the line names a file if such a file exists, otherwise each word does.
  std::vector<std::pair<std::string, fs::path>> names;  // as written, as found
  if (auto found = locate(folder, whole)) {
    names.push_back({whole, *found});
  } else {
    Tokens words(whole);
    size_t missing = 0;
    for (std::string_view w = words.next(); !w.empty(); w = words.next()) {
      const auto f = locate(folder, std::string(w));
      missing += f ? 0 : 1;
      names.push_back({std::string(w), f ? *f : folder / w});
    }
    // No word exists either: most likely one file name with spaces, so name it whole.
    if (missing == names.size()) fail_here("material library '{}' not found", excerpt(whole));
  }
  for (const auto& [name, mtl_path] : names) {
    const std::string key = mtl_path.lexically_normal().string();
    bool seen = false;
    for (const std::string& l : loaded_mtls_) seen = seen || l == key;
    if (seen) continue;
    std::string data;
    std::string reason;
    if (!read_whole_file(mtl_path, data, reason, /*regular_only=*/true)) fail_here("material library '{}' {}", excerpt(name), reason);
    loaded_mtls_.push_back(key);
    load_mtl(mtl_path, data);
  }
}

void ObjParser::load_mtl(const fs::path& mtl_path, const std::string& data) {
  const std::string mtl_name = mtl_path.lexically_normal().string();
  const fs::path folder = mtl_path.parent_path();
  size_t mtl_line = 0;
  if (std::memchr(data.data(), '\0', data.size()) != nullptr)
    fail_input("{}: not a text file (contains NUL bytes); expected a material library (MTL)", mtl_name);

  MaterialDef scratch;  // receives statements of a duplicate or before any newmtl
  MaterialDef* current = nullptr;
  LineReader lines(data);
  std::string_view line;
  while (lines.next(line)) {
    mtl_line = lines.number();
    Tokens tokens(line);
    const std::string_view keyword = tokens.next();
    if (keyword.empty()) continue;
    // MTL keywords are matched without case: exporters write both map_Kd and map_kd.
    if (equals_ignoring_case(keyword, "newmtl")) {
      const std::string_view name = tokens.rest();
      if (name.empty()) fail_at_line(mtl_name, mtl_line, "'newmtl' without a material name");
      const auto [it, inserted] = def_by_name_.try_emplace(std::string(name), defs_.size());
      if (inserted) {
        MaterialDef& def = defs_.emplace_back();
        def.material.name = std::string(name);
        def.mtl_path = mtl_name;
        current = &def;
      } else {
        // The first definition of a name wins, as usemtl cannot tell two of them apart.
        scratch = MaterialDef{};
        current = &scratch;
      }
    } else if (equals_ignoring_case(keyword, "Kd")) {
      // "Kd spectral file" and "Kd xyz x y z" are colour-space variants no scanner writes; keep the
      // default colour for them.
      const std::string_view first = tokens.peek();
      if (first == "spectral" || first == "xyz") continue;
      double rgb[3];
      size_t n = 0;
      for (std::string_view t = tokens.next(); !t.empty(); t = tokens.next()) {
        if (n == 3) fail_at_line(mtl_name, mtl_line, "too many values in 'Kd' (at most 3)");
        if (!parse_double(t, rgb[n])) fail_at_line(mtl_name, mtl_line, fmt::format("malformed number '{}' in 'Kd'", excerpt(t)));
        if (!std::isfinite(rgb[n])) fail_at_line(mtl_name, mtl_line, "NaN or infinite colour in 'Kd'");
        ++n;
      }
      if (n != 1 && n != 3) fail_at_line(mtl_name, mtl_line, fmt::format("'Kd' needs 1 or 3 values, got {}", n));
      if (n == 1) rgb[1] = rgb[2] = rgb[0];  // "Kd g" means grey g
      if (current != nullptr) current->material.kd = {rgb[0], rgb[1], rgb[2]};
    } else if (equals_ignoring_case(keyword, "map_Kd")) {
      std::array<double, 3> scale{1.0, 1.0, 1.0};
      std::array<double, 3> offset{0.0, 0.0, 0.0};
      read_map_kd_options(tokens, mtl_name, mtl_line, scale, offset);
      const std::string file = with_forward_slashes(tokens.rest());
      if (file.empty()) fail_at_line(mtl_name, mtl_line, "'map_Kd' without a file name");
      if (current == nullptr) continue;  // no material to attach it to
      // A texture tiled or shifted by -s/-o is sampled at the transformed coordinate; the mesh
      // keeps the transform per material (TexturedMesh::sampled_uv).
      current->material.uv_scale = {scale[0], scale[1]};
      current->material.uv_offset = {offset[0], offset[1]};
      current->texture_written = file;
      const std::optional<fs::path> found = locate(folder, file);
      current->texture_resolved = (found ? *found : folder / file).lexically_normal().string();
      current->texture_line = mtl_line;
    } else if (const int slot = mtl_map_slot(keyword); slot >= 0) {
      skip_map_options(tokens);
      const std::string file = with_forward_slashes(tokens.rest());
      if (file.empty() || current == nullptr) continue;
      const std::optional<fs::path> found = locate(folder, file);
      if (!found) {  // as before this map was read: the model is still usable without it
        not_read_.push_back(fmt::format("{}:{}: {} '{}' (file not found)", mtl_name, mtl_line, keyword, excerpt(file)));
        continue;
      }
      current->map_written[size_t(slot)] = file;
      current->map_resolved[size_t(slot)] = found->lexically_normal().string();
      current->map_line[size_t(slot)] = mtl_line;
    }
    // Every other statement (Ka, Ks, Ns, d, illum, PBR factors) does not affect the textures and is
    // ignored.
  }
}

void ObjParser::check_forward_refs() const {
  for (const ForwardRef& ref : forward_refs_) {
    const size_t defined = ref.kind == IndexKind::kVertex     ? positions_.size()
                           : ref.kind == IndexKind::kTexcoord ? texcoords_.size()
                                                              : normals_.size();
    if (uint64_t(ref.index) > defined)
      fail_input("{}:{}: {} index {} out of range (file has {} {})", path_, ref.line, kind_name(ref.kind), ref.index, defined,
                 kind_plural(ref.kind));
  }
}

void ObjParser::assemble_materials(TexturedMesh& mesh) {
  // Only materials that usemtl names enter the mesh, in order of first use: a library shared between
  // many models can define dozens, and loading their textures would cost seconds for nothing.
  std::vector<int32_t> material_of_use(uses_.size());
  std::vector<const MaterialDef*> used_defs;
  for (size_t u = 0; u < uses_.size(); ++u) {
    const auto it = def_by_name_.find(uses_[u].name);
    if (it == def_by_name_.end()) {
      if (!saw_mtllib_)
        fail_input("{}:{}: material '{}' used but the file names no material library (mtllib)", path_, uses_[u].first_line,
                   excerpt(uses_[u].name));
      fail_input("{}:{}: material '{}' is not defined in any material library", path_, uses_[u].first_line, excerpt(uses_[u].name));
    }
    material_of_use[u] = int32_t(used_defs.size());
    used_defs.push_back(&defs_[it->second]);
  }
  for (int32_t& m : mesh.face_material)
    if (m >= 0) m = material_of_use[size_t(m)];

  // One Texture per distinct resolved path, however many materials share it.
  std::unordered_map<std::string, int> texture_by_path;
  struct Source {  // the first statement naming each texture, to blame
    const MaterialDef* def;
    size_t line;
    const std::string* written;
  };
  std::vector<Source> texture_source;
  auto texture_of = [&](const MaterialDef* def, const std::string& resolved, size_t line, const std::string& written) {
    const auto [it, inserted] = texture_by_path.try_emplace(resolved, int(mesh.textures.size()));
    if (inserted) {
      mesh.textures.push_back(Texture{resolved, Image{}});
      texture_source.push_back({def, line, &written});
    }
    return it->second;
  };
  for (const MaterialDef* def : used_defs) {
    Material& m = mesh.materials.emplace_back(def->material);
    if (!def->texture_resolved.empty()) m.texture = texture_of(def, def->texture_resolved, def->texture_line, def->texture_written);
  }
  for (size_t u = 0; u < used_defs.size(); ++u)  // after every map_Kd: their textures keep their numbers
    for (size_t s = 0; s < kMapSlots; ++s)
      if (!used_defs[u]->map_resolved[s].empty())
        mesh.materials[u].maps[s] =
            texture_of(used_defs[u], used_defs[u]->map_resolved[s], used_defs[u]->map_line[s], used_defs[u]->map_written[s]);
  if (!options_.load_textures) return;

  // Errors are kept per texture and the first in file order is reported, so the message does not
  // depend on thread timing.
  const std::vector<std::string> errors = load_texture_images(mesh.textures, options_.max_texture_pixels);
  for (size_t i = 0; i < errors.size(); ++i) {
    if (errors[i].empty()) continue;
    const Source& src = texture_source[i];
    fail_input("{}:{}: texture '{}' of material '{}' could not be loaded: {}", src.def->mtl_path, src.line, excerpt(*src.written),
               excerpt(src.def->material.name), errors[i]);
  }
}

}  // namespace

TexturedMesh read_obj(const std::string& path, const ObjReadOptions& options, ObjReadStats* stats) {
  ObjParser parser(path, options);
  return parser.read(stats);
}

}  // namespace tightex
