// Wavefront OBJ + MTL reader. The whole file is read into memory, cut into stretches of whole lines,
// and each stretch is parsed on its own on every core (std::from_chars for numbers); a first pass
// counts each stretch's lines and elements, so relative indices and line numbers are the whole
// file's. Every problem is reported as "FILE:LINE: problem" on one line, the first in file order,
// whatever the stretches: what depends on the lines before (material uses, the all-or-nothing
// vertex colours, material libraries read as their line comes) is settled in file order afterwards.
//
// Things that cannot be checked while scanning (positive indices that point forward, usemtl before
// its mtllib, faces without texture coordinates) are recorded with their line and checked once the
// whole file is read, so the error still names the line that caused it.
#include "io/obj_reader.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string_view>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "io/image_io.hpp"
#include "io/model_files.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;

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

/// What a stretch of the file holds that the stretches after it count from: its lines ("FILE:LINE"),
/// the elements it defines (relative indices) and its triangles: where its own go in the whole
/// file's arrays.
struct ElementCounts {
  size_t lines = 0, v = 0, vt = 0, vn = 0, triangles = 0;

  ElementCounts operator+(const ElementCounts& o) const {
    return {lines + o.lines, v + o.v, vt + o.vt, vn + o.vn, triangles + o.triangles};
  }
};

/// Counts a stretch's lines, its v, vt and vn statements and the triangles of its faces (a face of n
/// corners is n - 2), each by its keyword and tokens as parse_line reads them: a stretch that parses
/// without error defines exactly these many elements.
ElementCounts count_elements(std::string_view text) {
  ElementCounts counts;
  LineReader lines(text);
  std::string_view line;
  while (lines.next(line)) {
    Tokens tokens(line);
    const std::string_view keyword = tokens.next();
    if (keyword == "v") {
      ++counts.v;
    } else if (keyword == "vt") {
      ++counts.vt;
    } else if (keyword == "f") {
      size_t corners = 0;
      while (!tokens.next().empty()) ++corners;
      counts.triangles += corners >= 3 ? corners - 2 : 0;
    } else if (keyword == "vn") {
      ++counts.vn;
    }
  }
  counts.lines = lines.number();
  return counts;
}

/// The text cut into stretches of about `bytes` each, every one ending after a line's '\n' (the last
/// at the end of the text), so that each parses on its own.
std::vector<std::string_view> split_at_lines(std::string_view text, size_t bytes) {
  std::vector<std::string_view> pieces;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.size();
    if (text.size() - start > bytes) {
      const size_t newline = text.find('\n', start + std::max<size_t>(bytes, 1) - 1);
      if (newline != std::string_view::npos) end = newline + 1;
    }
    pieces.push_back(text.substr(start, end - start));
    start = end;
  }
  return pieces;
}

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
  /// The other maps (MaterialSlot: map_Ks, map_Ke, map_Pr, map_Pm, norm, map_Bump / bump), as map_Kd's.
  std::array<std::string, kMaterialSlots> map_written, map_resolved;
  std::array<size_t, kMaterialSlots> map_line{};
};

/// The MaterialSlot an MTL keyword binds (matched without case), or -1: map_Ks specular colour, map_Ke
/// emissive, map_Pr roughness, map_Pm metallic, norm a tangent-space normal map, map_Bump / bump a
/// height map, map_d opacity, map_Ns shininess, disp / map_Disp displacement.
int mtl_map_slot(std::string_view keyword) {
  static constexpr std::pair<const char*, MaterialSlot> kKeywords[] = {
      {"map_Ks", MaterialSlot::kSpecular},   {"map_Ke", MaterialSlot::kEmissive},      {"map_Pr", MaterialSlot::kRoughness},
      {"map_Pm", MaterialSlot::kMetallic},   {"norm", MaterialSlot::kNormal},          {"map_Bump", MaterialSlot::kBump},
      {"bump", MaterialSlot::kBump},         {"map_d", MaterialSlot::kOpacity},        {"map_Ns", MaterialSlot::kShininess},
      {"disp", MaterialSlot::kDisplacement}, {"map_Disp", MaterialSlot::kDisplacement}};
  for (const auto& [word, slot] : kKeywords)
    if (equals_ignoring_case(keyword, word)) return int(slot);
  return -1;
}

/// Whether an MTL statement names an image that no slot reads: map_Ka, map_aat, refl, decal and any
/// other map_ keyword.
bool is_unread_map_statement(std::string_view keyword) {
  return (keyword.size() > 4 && equals_ignoring_case(keyword.substr(0, 4), "map_")) || equals_ignoring_case(keyword, "refl") ||
         equals_ignoring_case(keyword, "decal");
}

/// The slot whose factor an MTL scalar statement sets (Ks, Ke, Pr, Pm, d, Tr, Ns), and the number that
/// brings its value to a factor of 0..1 (Ns: 0..1000), or -1.
std::pair<int, double> mtl_scalar_slot(std::string_view keyword) {
  static constexpr std::tuple<const char*, MaterialSlot, double> kScalars[] = {
      {"Ks", MaterialSlot::kSpecular, 1},    {"Ke", MaterialSlot::kEmissive, 1}, {"Pr", MaterialSlot::kRoughness, 1},
      {"Pm", MaterialSlot::kMetallic, 1},    {"d", MaterialSlot::kOpacity, 1},   {"Tr", MaterialSlot::kOpacity, -1},
      {"Ns", MaterialSlot::kShininess, 1e-3}};
  for (const auto& [word, slot, scale] : kScalars)
    if (equals_ignoring_case(keyword, word)) return {int(slot), scale};
  return {-1, 0};
}

/// Sets material `m`'s factor of `slot` from an MTL scalar statement's values (one grey value or
/// three), times `scale` (Tr's -1: opacity is 1 - Tr); values that are not numbers leave it as it was,
/// as the statement is written back as it came.
void set_mtl_factor(Material& m, int slot, double scale, Tokens tokens) {
  double v[3];
  size_t n = 0;
  for (std::string_view t = tokens.next(); !t.empty() && n < 3; t = tokens.next())
    if (!parse_double(t, v[n++]) || !std::isfinite(v[n - 1])) return;
  if (n == 0) return;
  if (n < 3) v[1] = v[2] = v[0];
  SlotFactor& f = m.factor[size_t(slot)];
  for (size_t k = 0; k < 3; ++k) f[k] = scale < 0 ? 1 - v[k] : v[k] * scale;
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

/// An error found while parsing a stretch, reported only if nothing earlier in the file fails.
struct DeferredError {
  size_t line = 0;  // 0: none
  std::string message;
};

/// The whole file's elements and faces, each stretch's at its offset (ElementCounts before it).
struct ObjArrays {
  std::vector<Vec3> positions;
  std::vector<Vec2> texcoords;
  std::vector<Vec3> normals;
  std::vector<Tri> triangles;
  std::vector<uint32_t> corner_vt;  // 3 per triangle
  std::vector<uint32_t> corner_vn;  // 3 per triangle where the file has normals
  /// Per triangle, the material use: while parsing, the stretch's own number (ObjChunk::uses) or -1
  /// for the one in use where the stretch starts; then the file's (ObjParser::uses_), -1 before any.
  std::vector<int32_t> triangle_use;

  /// Allocated once at their final size, before the stretches fill them on every core.
  explicit ObjArrays(const ElementCounts& n) {
    allocate(positions, n.v);
    allocate(texcoords, n.vt);
    allocate(normals, n.vn);
    allocate(triangles, n.triangles);
    allocate(corner_vt, 3 * n.triangles);
    if (n.vn > 0) allocate(corner_vn, 3 * n.triangles);
    allocate(triangle_use, n.triangles);
  }
  template <typename T>
  static void allocate(std::vector<T>& v, size_t n) {
    reserve_prefaulted(v, n);
    v.resize(n);
  }
};

/// What one stretch of whole lines holds besides its elements (which go to ObjArrays), parsed on its
/// own with indices resolved against the whole file (the counts before it are known): what only file
/// order can settle, the material uses and libraries, the all-or-nothing colours and normals, the
/// first error.
struct ObjChunk {
  ElementCounts before;  // of the stretches before this one
  ElementCounts own;

  std::vector<std::array<float, 4>> vertex_colours;  // per vertex while every vertex so far has r g b
  bool all_vertices_coloured = true;
  bool colours_above_one = false;  // then the file writes colours as 0..255
  bool all_faces_have_normals = true;
  std::vector<MaterialUse> uses;                          // in order of first use in the stretch
  int32_t use_at_end = -1;                                // as triangle_use
  std::vector<std::pair<size_t, std::string>> libraries;  // mtllib: line, the rest of the line
  std::vector<ForwardRef> forward_refs;

  bool normals_finite = true;
  size_t first_face_without_vt = 0;  // line, 0 = none
  size_t polygons_triangulated = 0;
  // Statements tightex does not know (curves, surfaces, vp, ...); counted, not fatal. ModelReadStats
  // has no field for this yet.
  size_t unknown_statements = 0;

  /// A vertex colour out of range while every vertex of the stretch before it had one: an error only
  /// if every vertex before the stretch had one too (colours are all-or-nothing, as normals).
  DeferredError colour_error;
  DeferredError error;  // the first malformed line; parsing stops there
};

/// Parses one stretch into its ObjChunk and its part of ObjArrays.
class ChunkParser {
 public:
  ChunkParser(const std::string& path, ObjChunk& chunk, ObjArrays& all) : path_(path), chunk_(chunk), all_(all) {}

  void parse(std::string_view text);

 private:
  template <typename... Args>
  std::string message_here(fmt::format_string<Args...> f, Args&&... args) const {
    return fmt::format("{}:{}: {}", path_, line_, fmt::format(f, std::forward<Args>(args)...));
  }
  template <typename... Args>
  [[noreturn]] void fail_here(fmt::format_string<Args...> f, Args&&... args) const {
    throw InputError(message_here(f, std::forward<Args>(args)...));
  }

  void parse_line(std::string_view line);
  void parse_vertex(Tokens& tokens);
  void add_vertex_colour(const double* values, size_t n);
  void parse_texcoord(Tokens& tokens);
  void parse_normal(Tokens& tokens);
  void parse_face(Tokens& tokens);
  void parse_corner(std::string_view token, Corner& corner, bool& has_vt, bool& has_vn);
  uint32_t resolve_index(std::string_view text, IndexKind kind, std::string_view token);
  void parse_usemtl(std::string_view rest);
  size_t parse_numbers(Tokens& tokens, std::string_view keyword, double* out, size_t max_count);
  void check_coordinate(double value, std::string_view what) const;

  /// Where the next element of a kind goes in ObjArrays; fails (a bug, not the input) past what the
  /// first pass counted.
  size_t next_slot(size_t& written, size_t counted, size_t before) const {
    if (written == counted) fail_internal("{}:{}: more elements than counted", path_, line_);
    return before + written++;
  }

  const std::string& path_;
  ObjChunk& chunk_;
  ObjArrays& all_;
  ElementCounts written_;  // elements of the stretch so far
  size_t line_ = 0;
  std::vector<Corner> face_corners_;  // scratch for the face being parsed
  std::unordered_map<std::string, int32_t> use_by_name_;
};

void ChunkParser::parse(std::string_view text) {
  LineReader lines(text);
  std::string_view line;
  try {
    while (lines.next(line)) {
      line_ = chunk_.before.lines + lines.number();
      parse_line(line);
    }
  } catch (const InputError& e) {
    chunk_.error = {line_, e.what()};
  }
}

void ChunkParser::parse_line(std::string_view line) {
  Tokens tokens(line);
  const std::string_view keyword = tokens.next();
  if (keyword.empty()) return;  // blank line or comment
  // Most frequent first: v, vt and f make up nearly every line of a scan.
  if (keyword == "v") return parse_vertex(tokens);
  if (keyword == "vt") return parse_texcoord(tokens);
  if (keyword == "f") return parse_face(tokens);
  if (keyword == "vn") return parse_normal(tokens);
  if (keyword == "usemtl") return parse_usemtl(tokens.rest());
  if (keyword == "mtllib") {
    const std::string_view rest = tokens.rest();
    if (rest.empty()) fail_here("'mtllib' without a file name");
    chunk_.libraries.emplace_back(line_, std::string(rest));
    return;
  }
  // Object and group names, smoothing groups, and line and point elements carry nothing a texture
  // needs.
  if (keyword == "o" || keyword == "g" || keyword == "s" || keyword == "l" || keyword == "p") return;
  ++chunk_.unknown_statements;
}

/// Parses up to max_count numbers; fails on a malformed one or on more than max_count.
size_t ChunkParser::parse_numbers(Tokens& tokens, std::string_view keyword, double* out, size_t max_count) {
  size_t n = 0;
  for (std::string_view t = tokens.next(); !t.empty(); t = tokens.next()) {
    if (n == max_count) fail_here("too many values in '{}' (at most {})", keyword, max_count);
    if (!parse_double(t, out[n])) fail_here("malformed number '{}' in '{}'", excerpt(t), keyword);
    ++n;
  }
  return n;
}

void ChunkParser::check_coordinate(double value, std::string_view what) const {
  if (!std::isfinite(value)) fail_here("NaN or infinite {}", what);
  if (std::abs(value) > kAbsurdCoordinate) fail_here("absurd {} {:g} (absolute value above 1e15)", what, value);
}

void ChunkParser::parse_vertex(Tokens& tokens) {
  // x y z, then either w or r g b (vertex colours, written by scanners and MeshLab), possibly followed
  // by more numbers, which are checked and ignored.
  double values[7];
  const size_t n = parse_numbers(tokens, "v", values, 7);
  if (n < 3) fail_here("'v' needs 3 coordinates, got {}", n);
  for (size_t i = 0; i < 3; ++i) check_coordinate(values[i], "coordinate");
  if (chunk_.before.v + written_.v >= size_t(kNone) - 1) fail_here("too many vertices");
  all_.positions[next_slot(written_.v, chunk_.own.v, chunk_.before.v)] = Vec3(values[0], values[1], values[2]);
  add_vertex_colour(values, n);
}

/// `v x y z r g b`: the colour, kept while every vertex so far has one (all-or-nothing, as normals).
void ChunkParser::add_vertex_colour(const double* values, size_t n) {
  if (!chunk_.all_vertices_coloured) return;
  auto no_colours = [&] {
    chunk_.all_vertices_coloured = false;
    chunk_.vertex_colours = {};
  };
  if (n < 6) return no_colours();
  std::array<float, 4> c{0.0f, 0.0f, 0.0f, 1.0f};
  for (size_t k = 0; k < 3; ++k) {
    if (!std::isfinite(values[3 + k]) || values[3 + k] < 0) {
      chunk_.colour_error = {line_, message_here("vertex colour {:g} is not a number from 0 to 1 (or 0 to 255)", values[3 + k])};
      return no_colours();
    }
    chunk_.colours_above_one = chunk_.colours_above_one || values[3 + k] > 1.0;
    c[k] = float(values[3 + k]);
  }
  chunk_.vertex_colours.push_back(c);
}

void ChunkParser::parse_texcoord(Tokens& tokens) {
  double values[3] = {0.0, 0.0, 0.0};  // v and w default to 0 (OBJ specification)
  const size_t n = parse_numbers(tokens, "vt", values, 3);
  if (n < 1) fail_here("'vt' needs at least 1 value");
  for (size_t i = 0; i < 2; ++i) check_coordinate(values[i], "texture coordinate");
  if (chunk_.before.vt + written_.vt >= size_t(kNone) - 1) fail_here("too many texture coordinates");
  all_.texcoords[next_slot(written_.vt, chunk_.own.vt, chunk_.before.vt)] = Vec2(values[0], values[1]);
}

void ChunkParser::parse_normal(Tokens& tokens) {
  double values[3];
  const size_t n = parse_numbers(tokens, "vn", values, 3);
  if (n != 3) fail_here("'vn' needs 3 values, got {}", n);
  // Exporters write NaN normals for degenerate faces. Normals are optional, so such a file loses its
  // normals instead of being refused.
  if (!std::isfinite(values[0]) || !std::isfinite(values[1]) || !std::isfinite(values[2])) chunk_.normals_finite = false;
  if (chunk_.before.vn + written_.vn >= size_t(kNone) - 1) fail_here("too many normals");
  all_.normals[next_slot(written_.vn, chunk_.own.vn, chunk_.before.vn)] = Vec3(values[0], values[1], values[2]);
}

uint32_t ChunkParser::resolve_index(std::string_view text, IndexKind kind, std::string_view token) {
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
  const size_t defined = kind == IndexKind::kVertex     ? chunk_.before.v + written_.v
                         : kind == IndexKind::kTexcoord ? chunk_.before.vt + written_.vt
                                                        : chunk_.before.vn + written_.vn;
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
    chunk_.forward_refs.push_back({line_, index, kind});
  }
  return uint32_t(index - 1);
}

void ChunkParser::parse_corner(std::string_view token, Corner& corner, bool& has_vt, bool& has_vn) {
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

void ChunkParser::parse_face(Tokens& tokens) {
  face_corners_.clear();
  bool has_vt = true, has_vn = true;
  for (std::string_view t = tokens.next(); !t.empty(); t = tokens.next()) {
    Corner& c = face_corners_.emplace_back();
    parse_corner(t, c, has_vt, has_vn);
  }
  const size_t n = face_corners_.size();
  if (n < 3) fail_here("face has {} corner{} (needs at least 3)", n, n == 1 ? "" : "s");
  if (!has_vt && chunk_.first_face_without_vt == 0) chunk_.first_face_without_vt = line_;
  // Normals are all-or-nothing, so the normal indices are of no use from here on.
  if (!has_vn) chunk_.all_faces_have_normals = false;
  if (n > 3) ++chunk_.polygons_triangulated;
  // Fan around the first corner: exact for the convex polygons exporters write, and it keeps the
  // polygon's winding.
  for (size_t i = 1; i + 1 < n; ++i) {
    const Corner& a = face_corners_[0];
    const Corner& b = face_corners_[i];
    const Corner& c = face_corners_[i + 1];
    const size_t t = next_slot(written_.triangles, chunk_.own.triangles, chunk_.before.triangles);
    all_.triangles[t] = {a.v, b.v, c.v};
    std::copy_n(std::array{a.vt, b.vt, c.vt}.begin(), 3, all_.corner_vt.begin() + ptrdiff_t(3 * t));
    if (chunk_.all_faces_have_normals && !all_.corner_vn.empty())
      std::copy_n(std::array{a.vn, b.vn, c.vn}.begin(), 3, all_.corner_vn.begin() + ptrdiff_t(3 * t));
    all_.triangle_use[t] = chunk_.use_at_end;
  }
}

void ChunkParser::parse_usemtl(std::string_view rest) {
  if (rest.empty()) fail_here("'usemtl' without a material name");
  const std::string name(rest);
  const auto [it, inserted] = use_by_name_.try_emplace(name, int32_t(chunk_.uses.size()));
  if (inserted) chunk_.uses.push_back({name, line_});
  chunk_.use_at_end = it->second;
}

class ObjParser {
 public:
  ObjParser(const std::string& path, const ModelReadOptions& options, size_t chunk_bytes)
      : path_(path), options_(options), chunk_bytes_(chunk_bytes) {}

  TexturedMesh read(ModelReadStats* stats);

 private:
  template <typename... Args>
  [[noreturn]] void fail_here(fmt::format_string<Args...> f, Args&&... args) const {
    fail_input("{}:{}: {}", path_, line_, fmt::format(f, std::forward<Args>(args)...));
  }

  std::vector<ObjChunk> parse_in_chunks(std::string_view text);
  void settle_in_file_order(const std::vector<ObjChunk>& chunks);
  void number_uses(std::vector<ObjChunk>& chunks);
  void gather(std::vector<ObjChunk>& chunks);
  void parse_mtllib(std::string_view rest);
  void load_mtl(const fs::path& mtl_path, const std::string& data);

  void check_forward_refs() const;
  bool coloured() const;
  void check_texture_coordinates() const;
  void assemble_uvs(TexturedMesh& mesh) const;
  void assemble_colours(TexturedMesh& mesh) const;
  void assemble_materials(TexturedMesh& mesh);

  const std::string& path_;
  const ModelReadOptions& options_;
  const size_t chunk_bytes_;
  size_t line_ = 0;  // of the mtllib being read

  // The whole file's, gathered from its stretches.
  std::vector<Vec3> positions_;
  std::vector<Vec2> texcoords_;
  std::vector<Vec3> normals_;
  std::vector<std::array<float, 4>> vertex_colours_;
  bool all_vertices_coloured_ = true;
  bool colours_above_one_ = false;
  std::vector<Tri> triangles_;
  std::vector<uint32_t> corner_vt_;
  std::vector<uint32_t> corner_vn_;
  std::vector<int32_t> triangle_use_;  // index into uses_, -1 before any usemtl
  std::vector<ForwardRef> forward_refs_;
  bool all_faces_have_normals_ = true;
  bool normals_finite_ = true;
  size_t first_face_without_vt_ = 0;
  size_t polygons_triangulated_ = 0;
  size_t lines_ = 0;

  std::vector<MaterialUse> uses_;
  std::unordered_map<std::string, int32_t> use_by_name_;

  std::vector<MaterialDef> defs_;
  std::unordered_map<std::string, size_t> def_by_name_;  // first definition of a name wins
  std::vector<std::string> loaded_mtls_;                 // each library is read once
  std::vector<std::string> paths_found_;                 // ModelReadStats::paths_found
  std::vector<std::string> not_read_;                    // ModelReadStats::not_read: maps whose file is missing
  /// find_named_file, noting in paths_found_ a file found under another name than written; a refused
  /// reference fails with "WHERE 'written' why" (`where`: "FILE:LINE: map_Kd").
  std::optional<fs::path> locate(const fs::path& folder, const std::string& written, const std::string& where) {
    NamedFile named = find_named_file(folder, written, options_.allow_outside_files);
    if (!named.refused.empty()) fail_input("{} '{}' {}", where, excerpt(written), named.refused);
    std::optional<fs::path>& found = named.path;
    if (found && *found != folder / written) paths_found_.push_back(fmt::format("{} -> {}", written, found->lexically_normal().string()));
    return found;
  }
  bool saw_mtllib_ = false;
  bool coloured_file_ = false;         // every vertex of the file has a colour (settle_in_file_order)
  std::string missing_library_;        // the first mtllib not found, "FILE:LINE: problem"; empty: none
  std::vector<std::string> warnings_;  // ModelReadStats::warnings
};

TexturedMesh ObjParser::read(ModelReadStats* stats) {
  std::string data;
  std::string reason;
  if (!read_whole_file(path_, data, reason)) fail_input("{}: {}", path_, reason);
  // A binary file (a PNG or a PLY picked by mistake) would otherwise "parse" as unknown statements
  // and end in a puzzling "no faces".
  if (std::memchr(data.data(), '\0', data.size()) != nullptr)
    fail_input("{}: not a text file (contains NUL bytes); expected a Wavefront OBJ", path_);
  std::vector<ObjChunk> chunks = parse_in_chunks(data);
  settle_in_file_order(chunks);
  number_uses(chunks);
  gather(chunks);
  chunks = {};

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
    tbb::parallel_for(tbb::blocked_range<size_t>(0, corner_vn_.size(), size_t(1) << 16), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) mesh.corner_normal[i] = normals_[corner_vn_[i]];
    });
  }
  mesh.face_material = std::move(triangle_use_);
  if (!missing_library_.empty()) warnings_.push_back(missing_library_ + ": the vertex colours are read without its materials");
  assemble_materials(mesh);

  if (stats != nullptr) {
    stats->polygons_triangulated = polygons_triangulated_;
    stats->lines = lines_;
    stats->paths_found = paths_found_;
    stats->not_read = not_read_;
    stats->warnings.insert(stats->warnings.end(), warnings_.begin(), warnings_.end());
  }
  return mesh;
}

/// Counts each stretch's lines and elements (one pass on every core), so that each knows what comes
/// before it and where its elements go, then parses them on every core into the arrays allocated
/// once.
std::vector<ObjChunk> ObjParser::parse_in_chunks(std::string_view text) {
  const std::vector<std::string_view> pieces = split_at_lines(text, chunk_bytes_);
  std::vector<ObjChunk> chunks(pieces.size());
  tbb::parallel_for(size_t(0), pieces.size(), [&](size_t i) { chunks[i].own = count_elements(pieces[i]); });
  for (size_t i = 1; i < chunks.size(); ++i) chunks[i].before = chunks[i - 1].before + chunks[i - 1].own;
  ObjArrays all(chunks.empty() ? ElementCounts{} : chunks.back().before + chunks.back().own);
  tbb::parallel_for(size_t(0), pieces.size(), [&](size_t i) { ChunkParser(path_, chunks[i], all).parse(pieces[i]); });
  positions_ = std::move(all.positions);
  texcoords_ = std::move(all.texcoords);
  normals_ = std::move(all.normals);
  triangles_ = std::move(all.triangles);
  corner_vt_ = std::move(all.corner_vt);
  corner_vn_ = std::move(all.corner_vn);
  triangle_use_ = std::move(all.triangle_use);
  return chunks;
}

/// Raises the file's first error, as a reader going line by line would: a malformed line, or a bad
/// vertex colour while every vertex before had one, or a material library (read as its line comes)
/// that fails before either.
void ObjParser::settle_in_file_order(const std::vector<ObjChunk>& chunks) {
  const DeferredError* first_error = nullptr;
  bool coloured_before = true;
  for (const ObjChunk& c : chunks) {
    if (coloured_before && c.colour_error.line != 0) {
      first_error = &c.colour_error;
      break;
    }
    if (c.error.line != 0) {
      first_error = &c.error;
      break;
    }
    coloured_before = coloured_before && c.all_vertices_coloured;
  }
  coloured_file_ = first_error == nullptr && !chunks.empty();
  bool any_colour = false;
  for (const ObjChunk& c : chunks)
    coloured_file_ = coloured_file_ && c.all_vertices_coloured, any_colour = any_colour || !c.vertex_colours.empty();
  coloured_file_ = coloured_file_ && any_colour;
  for (const ObjChunk& c : chunks)
    for (const auto& [line, rest] : c.libraries) {
      if (first_error != nullptr && line > first_error->line) break;
      line_ = line;
      parse_mtllib(rest);
    }
  line_ = 0;
  if (first_error != nullptr) throw InputError(first_error->message);
}

/// Numbers the usemtl names in order of first use in the file, and every triangle's use by those
/// numbers; a stretch's triangles before its first usemtl take the material in use where it starts.
void ObjParser::number_uses(std::vector<ObjChunk>& chunks) {
  int32_t in_use = -1;
  for (ObjChunk& c : chunks) {
    std::vector<int32_t> number(c.uses.size());
    for (size_t u = 0; u < c.uses.size(); ++u) {
      const auto [it, inserted] = use_by_name_.try_emplace(c.uses[u].name, int32_t(uses_.size()));
      if (inserted) uses_.push_back(c.uses[u]);
      number[u] = it->second;
    }
    if (!c.uses.empty() || in_use >= 0)
      for (size_t t = c.before.triangles; t < c.before.triangles + c.own.triangles; ++t)
        triangle_use_[t] = triangle_use_[t] < 0 ? in_use : number[size_t(triangle_use_[t])];
    if (c.use_at_end >= 0) in_use = number[size_t(c.use_at_end)];
  }
}

/// The whole file's flags, forward references and vertex colours from its stretches'.
void ObjParser::gather(std::vector<ObjChunk>& chunks) {
  for (const ObjChunk& c : chunks) {
    all_vertices_coloured_ = all_vertices_coloured_ && c.all_vertices_coloured;
    colours_above_one_ = colours_above_one_ || c.colours_above_one;
    all_faces_have_normals_ = all_faces_have_normals_ && c.all_faces_have_normals;
    normals_finite_ = normals_finite_ && c.normals_finite;
    if (first_face_without_vt_ == 0) first_face_without_vt_ = c.first_face_without_vt;
    polygons_triangulated_ += c.polygons_triangulated;
    lines_ += c.own.lines;
    forward_refs_.insert(forward_refs_.end(), c.forward_refs.begin(), c.forward_refs.end());
  }
  if (all_vertices_coloured_) {
    vertex_colours_.reserve(positions_.size());
    for (ObjChunk& c : chunks) {
      vertex_colours_.insert(vertex_colours_.end(), c.vertex_colours.begin(), c.vertex_colours.end());
      c.vertex_colours = {};
    }
  }
  if (!all_faces_have_normals_) corner_vn_ = {};
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
  tbb::parallel_for(tbb::blocked_range<size_t>(0, corner_vt_.size(), size_t(1) << 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) mesh.corner_uv[i] = corner_vt_[i] == kNone ? Vec2::Zero() : texcoords_[corner_vt_[i]];
  });
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

void ObjParser::parse_mtllib(std::string_view rest) {
  saw_mtllib_ = true;
  const fs::path folder = fs::path(path_).parent_path();
  const std::string whole = with_forward_slashes(rest);
  // mtllib may list several files separated by blanks, but a single file name may also contain
  // spaces: the whole rest of the line names a file if such a file exists, otherwise each word does.
  std::vector<std::pair<std::string, fs::path>> names;  // as written, as found
  const std::string where = fmt::format("{}:{}: material library", path_, line_);
  if (auto found = locate(folder, whole, where)) {
    names.push_back({whole, *found});
  } else {
    Tokens words(whole);
    size_t missing = 0;
    for (std::string_view w = words.next(); !w.empty(); w = words.next()) {
      const auto f = locate(folder, std::string(w), where);
      missing += f ? 0 : 1;
      names.push_back({std::string(w), f ? *f : folder / w});
    }
    // No word exists either: most likely one file name with spaces, so name it whole. A vertex-coloured
    // model is read without it, with a warning.
    if (missing == names.size()) {
      if (!coloured_file_) fail_here("material library '{}' not found", excerpt(whole));
      if (missing_library_.empty()) missing_library_ = fmt::format("{}:{}: material library '{}' not found", path_, line_, excerpt(whole));
      return;
    }
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
      const std::optional<fs::path> found = locate(folder, file, fmt::format("{}:{}: map_Kd", mtl_name, mtl_line));
      current->texture_resolved = (found ? *found : folder / file).lexically_normal().string();
      current->texture_line = mtl_line;
    } else if (const int slot = mtl_map_slot(keyword); slot >= 0) {
      skip_map_options(tokens);
      const std::string file = with_forward_slashes(tokens.rest());
      if (file.empty() || current == nullptr) continue;
      const std::optional<fs::path> found = locate(folder, file, fmt::format("{}:{}: {}", mtl_name, mtl_line, keyword));
      if (!found) {  // as before this map was read: the model is still usable without it
        not_read_.push_back(fmt::format("{}:{}: {} '{}' (file not found)", mtl_name, mtl_line, keyword, excerpt(file)));
        continue;
      }
      current->map_written[size_t(slot)] = file;
      current->map_resolved[size_t(slot)] = found->lexically_normal().string();
      current->map_line[size_t(slot)] = mtl_line;
    } else if (is_unread_map_statement(keyword)) {
      // A map with no slot (map_Ka, refl, decal, ...) would name a file the output does not have.
      if (current != nullptr) not_read_.push_back(fmt::format("{}:{}: {} (no slot for it: not kept)", mtl_name, mtl_line, keyword));
    } else if (current != nullptr) {
      // Every other statement (Ka, Ks, Ns, d, illum, PBR factors) is kept as it came for write_obj;
      // the scalars of the slots (Ks, Ke, Pr, Pm, d, Tr, Ns) are the slots' factors.
      current->material.mtl_statements.emplace_back(line);
      if (const auto [scalar_slot, scale] = mtl_scalar_slot(keyword); scalar_slot >= 0)
        set_mtl_factor(current->material, scalar_slot, scale, tokens);
    }
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
    if (it == def_by_name_.end() && !missing_library_.empty()) {
      material_of_use[u] = -1;  // its library is missing: the vertex colours show (read())
      continue;
    }
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
  // A texture's load error blames the first statement naming it.
  std::unordered_map<std::string, int> texture_by_path;
  auto texture_of = [&](const MaterialDef* def, const std::string& resolved, size_t line, const std::string& written) {
    const auto [it, inserted] = texture_by_path.try_emplace(resolved, int(mesh.textures.size()));
    if (inserted) {
      Texture& t = mesh.textures.emplace_back(Texture{resolved, Image{}});
      t.named_at = fmt::format("{}:{}: texture '{}' of material '{}'", def->mtl_path, line, excerpt(written), excerpt(def->material.name));
    }
    return it->second;
  };
  for (const MaterialDef* def : used_defs) {
    Material& m = mesh.materials.emplace_back(def->material);
    if (!def->texture_resolved.empty()) m.texture = texture_of(def, def->texture_resolved, def->texture_line, def->texture_written);
  }
  for (size_t u = 0; u < used_defs.size(); ++u)  // after every map_Kd: their textures keep their numbers
    for (size_t s = 0; s < kMaterialSlots; ++s)
      if (!used_defs[u]->map_resolved[s].empty()) {
        mesh.materials[u].maps[s] =
            texture_of(used_defs[u], used_defs[u]->map_resolved[s], used_defs[u]->map_line[s], used_defs[u]->map_written[s]);
        mesh.materials[u].factor[s] = {1, 1, 1, 1};  // OBJ viewers show a map alone, as they show map_Kd
      }
  if (options_.load_textures) mesh.textures = load_texture_pixels(mesh, options_.max_texture_pixels);
}

}  // namespace

TexturedMesh read_obj_in_chunks(const std::string& path, const ModelReadOptions& options, ModelReadStats* stats, size_t chunk_bytes) {
  ObjParser parser(path, options, chunk_bytes);
  return parser.read(stats);
}

TexturedMesh read_obj(const std::string& path, const ModelReadOptions& options, ModelReadStats* stats) {
  return read_obj_in_chunks(path, options, stats, kObjChunkBytes);
}

}  // namespace tightex
