// PLY reader. The whole file is read into memory; the header is parsed and checked first
// (io/ply_header.cpp), then the body is read element by element in the header's order, each value
// converted to double (exact for every PLY type), with every problem reported on one line naming the
// file, the element and the entry (and, in ascii, the line). An ascii file's vertices and faces, one
// entry a line as writers put them, are read in blocks of lines on every core; where a block does not
// hold exactly its entries, or has an error, the element is read again in one pass, which reports it.
#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

#include "core/error.hpp"
#include "io/model_files.hpp"
#include "io/ply_header.hpp"
#include "io/ply_reader.hpp"
#include "tightex/io.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;

// Corners of one polygon: more than any scan's faces, few enough that a lying list size cannot make
// the scratch arrays large.
constexpr size_t kMaxCorners = 1024;

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

/// The body after the header: values read one at a time as the header declares them, ascii or binary,
/// with the element and entry being read kept for messages.
class PlyBody {
 public:
  PlyBody(const std::string& file, std::string_view body, PlyFormat format, size_t header_lines)
      : file_(file), p_(body.data()), end_(body.data() + body.size()), format_(format), line_(header_lines + 1) {
    swap_ = format != PlyFormat::kAscii && (format == PlyFormat::kBinaryBigEndian) != (std::endian::native == std::endian::big);
  }

  /// The element and entry that messages name from now on.
  void at(const std::string& element, uint64_t index) {
    element_ = &element;
    index_ = index;
  }
  /// One value of `type`.
  double value(PlyType type) { return format_ == PlyFormat::kAscii ? ascii_value(type) : binary_value(type); }
  /// A list's size (of type `count_type`), refused above `max_size` (`what` names the list).
  size_t list_size(PlyType count_type, size_t max_size, std::string_view what);
  /// Reads past one property's value (or list) without keeping it.
  void skip(const PlyProperty& p);
  /// Text lines of the body read so far (0 for binary).
  size_t lines_read(size_t header_lines) const { return format_ == PlyFormat::kAscii ? line_ - header_lines - 1 : 0; }
  /// Where the next value is read from, and where the body ends.
  const char* position() const { return p_; }
  const char* end() const { return end_; }
  /// Moves on to `p` (at or after position(), within the body), counting the lines passed.
  void advance_to(const char* p) {
    line_ += size_t(std::count(p_, p, '\n'));
    p_ = p;
  }
  /// Ends an entry (ascii): what is left of its last value's line must be blank, so a line holding more
  /// values than the header declares is refused at that line, not one line later.
  void end_entry() {
    if (format_ != PlyFormat::kAscii) return;
    while (p_ < end_ && *p_ != '\n' && is_space(*p_)) ++p_;
    if (p_ < end_ && *p_ != '\n') fail("more values on the line than the header declares (from '{}')", excerpt(next_token()));
  }
  /// Whether only blanks are left (ascii).
  bool only_blanks_left() {
    while (p_ < end_ && is_space(*p_)) ++p_;
    return p_ == end_;
  }

  template <typename... Args>
  [[noreturn]] void fail(fmt::format_string<Args...> f, Args&&... args) const {
    const std::string problem = fmt::format(f, std::forward<Args>(args)...);
    const std::string element = element_ != nullptr ? excerpt(*element_) : std::string("body");
    if (format_ == PlyFormat::kAscii) fail_input("{}:{}: {} {}: {}", file_, line_, element, index_, problem);
    fail_input("{}: {} {}: {}", file_, element, index_, problem);
  }

 private:
  double ascii_value(PlyType type);
  double binary_value(PlyType type);
  std::string_view next_token();
  [[noreturn]] void fail_truncated() const { fail("the file ends early (truncated)"); }

  const std::string& file_;
  const char* p_;
  const char* end_;
  PlyFormat format_;
  bool swap_ = false;
  size_t line_;
  const std::string* element_ = nullptr;
  uint64_t index_ = 0;
};

std::string_view PlyBody::next_token() {
  while (p_ < end_ && is_space(*p_)) {
    if (*p_ == '\n') ++line_;
    ++p_;
  }
  const char* start = p_;
  while (p_ < end_ && !is_space(*p_)) ++p_;
  return {start, size_t(p_ - start)};
}

double PlyBody::ascii_value(PlyType type) {
  const std::string_view token = next_token();
  if (token.empty()) fail_truncated();
  double v = 0.0;
  if (!parse_double(token, v)) fail("malformed number '{}'", excerpt(token));
  if (!is_integer(type)) return v;
  const size_t bits = 8 * type_size(type);
  const bool is_signed = type == PlyType::kInt8 || type == PlyType::kInt16 || type == PlyType::kInt32;
  const double lo = is_signed ? -std::ldexp(1.0, int(bits) - 1) : 0.0;
  const double hi = is_signed ? std::ldexp(1.0, int(bits) - 1) - 1 : std::ldexp(1.0, int(bits)) - 1;
  if (!(v == std::floor(v) && v >= lo && v <= hi)) fail("'{}' is not a value of type {}", excerpt(token), type_name(type));
  return v;
}

/// A value of T stored at `p` in the file's byte order.
template <typename T>
T load(const char* p, bool swap) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, p, sizeof(T));
  if (swap)
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
  T v;
  std::memcpy(&v, bytes, sizeof(T));
  return v;
}

double PlyBody::binary_value(PlyType type) {
  const size_t size = type_size(type);
  if (size_t(end_ - p_) < size) fail_truncated();
  const char* at = p_;
  p_ += size;
  switch (type) {
    case PlyType::kInt8:
      return load<int8_t>(at, swap_);
    case PlyType::kUint8:
      return load<uint8_t>(at, swap_);
    case PlyType::kInt16:
      return load<int16_t>(at, swap_);
    case PlyType::kUint16:
      return load<uint16_t>(at, swap_);
    case PlyType::kInt32:
      return load<int32_t>(at, swap_);
    case PlyType::kUint32:
      return load<uint32_t>(at, swap_);
    case PlyType::kFloat32:
      return double(load<float>(at, swap_));
    case PlyType::kFloat64:
      return load<double>(at, swap_);
  }
  return 0.0;
}

size_t PlyBody::list_size(PlyType count_type, size_t max_size, std::string_view what) {
  const double n = value(count_type);
  if (n < 0) fail("negative size {} of list '{}'", n, excerpt(what));
  if (n > double(max_size)) fail("list '{}' of {} values (at most {})", excerpt(what), n, max_size);
  return size_t(n);
}

void PlyBody::skip(const PlyProperty& p) {
  if (!p.is_list) {
    (void)value(p.type);
    return;
  }
  const double n = value(p.count_type);
  if (n < 0) fail("negative size {} of list '{}'", n, excerpt(p.name));
  if (format_ == PlyFormat::kAscii) {
    // Each value is a token of its own; a size beyond the file ends in "truncated".
    for (uint64_t i = 0; i < uint64_t(n); ++i)
      if (next_token().empty()) fail_truncated();
    return;
  }
  const size_t bytes_left = size_t(end_ - p_);
  if (n > double(bytes_left / type_size(p.type))) fail_truncated();
  p_ += size_t(n) * type_size(p.type);
}

/// One vertex as read.
struct VertexEntry {
  Vec3 position = Vec3::Zero();
  Vec2 uv = Vec2::Zero();
  std::array<float, 4> colour{0.0f, 0.0f, 0.0f, 1.0f};
};

/// One face as read, before it is triangulated.
struct FaceEntry {
  std::vector<uint32_t> corners;
  std::vector<double> texcoord;
  int32_t texnumber = 0;
  std::array<float, 4> colour{0.0f, 0.0f, 0.0f, 1.0f};
};

/// The largest value of an integer type: colours stored as integers span 0 to it (uchar 255).
double integer_full_scale(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
      return 127.0;
    case PlyType::kUint8:
      return 255.0;
    case PlyType::kInt16:
      return 32767.0;
    case PlyType::kUint16:
      return 65535.0;
    case PlyType::kInt32:
      return 2147483647.0;
    case PlyType::kUint32:
      return 4294967295.0;
    default:
      return 1.0;
  }
}

/// Faces as read, triangulated: each triangle with what its face carries.
struct FaceArrays {
  std::vector<Tri> triangles;
  std::vector<Vec2> corner_uv;                    // 3 per triangle, from the faces' texcoord lists
  std::vector<int32_t> face_texture;              // per triangle: texnumber, -1 for none
  std::vector<std::array<float, 4>> face_colour;  // per triangle, when the face element has colours
  size_t polygons_triangulated = 0;

  /// Room for all of `parts` at once, so that appending them copies each once.
  void reserve_for(const std::vector<FaceArrays>& parts) {
    size_t t = 0, uv = 0, colours = 0;
    for (const FaceArrays& p : parts) t += p.triangles.size(), uv += p.corner_uv.size(), colours += p.face_colour.size();
    triangles.reserve(triangles.size() + t);
    face_texture.reserve(face_texture.size() + t);
    corner_uv.reserve(corner_uv.size() + uv);
    face_colour.reserve(face_colour.size() + colours);
  }
  void append(const FaceArrays& more) {
    triangles.insert(triangles.end(), more.triangles.begin(), more.triangles.end());
    corner_uv.insert(corner_uv.end(), more.corner_uv.begin(), more.corner_uv.end());
    face_texture.insert(face_texture.end(), more.face_texture.begin(), more.face_texture.end());
    face_colour.insert(face_colour.end(), more.face_colour.begin(), more.face_colour.end());
    polygons_triangulated += more.polygons_triangulated;
  }
};

/// Where the blocks of an ascii element of `count` entries would start if each entry is a line of its
/// own from `from` on: at `from`, then every block_entries-th line after the line of the first value,
/// and last where the count-th line ends. Empty where the text has fewer lines.
std::vector<const char*> block_bounds(const char* from, const char* end, uint64_t count, uint64_t block_entries) {
  const char* line = from;
  while (line < end && is_space(*line)) ++line;
  std::vector<const char*> bounds{from};
  for (uint64_t entry = 1; entry <= count; ++entry) {
    const char* newline = static_cast<const char*>(std::memchr(line, '\n', size_t(end - line)));
    if (newline == nullptr) {
      if (entry < count) return {};
      newline = end;
    }
    line = entry < count ? newline + 1 : newline;
    if (entry % block_entries == 0 || entry == count) bounds.push_back(line);
  }
  return bounds;
}

class PlyReader {
 public:
  PlyReader(const std::string& path, const ModelReadOptions& options, uint64_t block_entries)
      : path_(path), options_(options), block_entries_(std::max<uint64_t>(block_entries, 1)) {}
  TexturedMesh read(ModelReadStats* stats);

 private:
  void read_vertices(PlyBody& body, const PlyElement& e);
  void read_vertex(PlyBody& body, const PlyElement& e, VertexEntry& vertex) const;
  void keep_vertex(size_t index, const VertexEntry& vertex);
  void read_faces(PlyBody& body, const PlyElement& e);
  void read_face(PlyBody& body, const PlyElement& e, FaceEntry& face) const;
  void add_face(PlyBody& body, const FaceEntry& face, FaceArrays& out) const;
  template <class ReadBlock>
  bool read_in_blocks(PlyBody& body, uint64_t count, ReadBlock&& read_block) const;
  void skip_element(PlyBody& body, const PlyElement& e);
  static double coordinate(PlyBody& body, PlyType type, std::string_view what);
  static float colour_value(PlyBody& body, PlyType type);
  void assemble_colours(TexturedMesh& mesh);
  void assemble_uvs(TexturedMesh& mesh);
  void assemble_materials(TexturedMesh& mesh);

  const std::string& path_;
  const ModelReadOptions& options_;
  const uint64_t block_entries_;  // of an ascii element read in blocks (kPlyBlockEntries)
  PlyHeader header_;

  std::vector<Vec3> positions_;
  std::vector<Vec2> vertex_uv_;                      // per vertex, when the vertex element has a pair
  std::vector<std::array<float, 4>> vertex_colour_;  // per vertex, when the vertex element has colours
  FaceArrays faces_;
  std::vector<std::string> paths_found_;
};

double PlyReader::coordinate(PlyBody& body, PlyType type, std::string_view what) {
  const double v = body.value(type);
  if (!std::isfinite(v)) body.fail("NaN or infinite {}", what);
  if (std::abs(v) > kAbsurdCoordinate) body.fail("absurd {} {:g} (absolute value above 1e15)", what, v);
  return v;
}

/// A colour channel in [0, 1]: integers as a fraction of their type's full scale, floats as they are;
/// out of range values are clamped (some writers round past 1), NaN refused.
float PlyReader::colour_value(PlyBody& body, PlyType type) {
  const double v = body.value(type);
  if (std::isnan(v)) body.fail("NaN colour");
  return float(std::clamp(is_integer(type) ? v / integer_full_scale(type) : v, 0.0, 1.0));
}

/// Reads an ascii element of `count` entries in blocks of lines side by side: read_block(block_body,
/// first, end) reads entries [first, end) from a body over its block's text and returns where its last
/// value ended. True, with `body` moved past the element, where every block read exactly its entries;
/// false, `body` untouched, otherwise (the caller then reads the element in one pass).
template <class ReadBlock>
bool PlyReader::read_in_blocks(PlyBody& body, uint64_t count, ReadBlock&& read_block) const {
  if (header_.format != PlyFormat::kAscii || count / 2 < block_entries_) return false;
  const std::vector<const char*> bounds = block_bounds(body.position(), body.end(), count, block_entries_);
  if (bounds.empty()) return false;
  const size_t blocks = bounds.size() - 1;
  std::vector<char> exact(blocks, 0);
  const char* last_value_end = nullptr;
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    try {
      PlyBody block(path_, std::string_view(bounds[b], size_t(bounds[b + 1] - bounds[b])), PlyFormat::kAscii, 0);
      const char* value_end = read_block(block, uint64_t(b) * block_entries_, std::min(count, uint64_t(b + 1) * block_entries_));
      if (b + 1 == blocks) last_value_end = value_end;
      exact[b] = block.only_blanks_left();
    } catch (const std::exception&) {
      exact[b] = 0;
    }
  });
  if (std::find(exact.begin(), exact.end(), 0) != exact.end()) return false;
  body.advance_to(last_value_end);
  return true;
}

void PlyReader::read_vertex(PlyBody& body, const PlyElement& e, VertexEntry& vertex) const {
  vertex = VertexEntry{};
  for (const PlyProperty& prop : e.properties) {
    switch (prop.role) {
      case PlyRole::kX:
      case PlyRole::kY:
      case PlyRole::kZ:
        vertex.position[int(prop.role) - int(PlyRole::kX)] = coordinate(body, prop.type, "coordinate");
        break;
      case PlyRole::kU:
      case PlyRole::kV:
        vertex.uv[int(prop.role) - int(PlyRole::kU)] = coordinate(body, prop.type, "texture coordinate");
        break;
      case PlyRole::kRed:
      case PlyRole::kGreen:
      case PlyRole::kBlue:
      case PlyRole::kAlpha:
        vertex.colour[size_t(int(prop.role) - int(PlyRole::kRed))] = colour_value(body, prop.type);
        break;
      default:
        body.skip(prop);
    }
  }
  body.end_entry();
}

void PlyReader::keep_vertex(size_t index, const VertexEntry& vertex) {
  positions_[index] = vertex.position;
  if (header_.vertex_uv) vertex_uv_[index] = vertex.uv;
  if (header_.vertex_color) vertex_colour_[index] = vertex.colour;
}

void PlyReader::read_vertices(PlyBody& body, const PlyElement& e) {
  if (e.count >= uint64_t(kNone)) body.fail("too many vertices ({})", e.count);
  // The header's counts were weighed against the file's size: these fit in memory.
  positions_.resize(size_t(e.count));
  if (header_.vertex_uv) vertex_uv_.resize(size_t(e.count));
  if (header_.vertex_color) vertex_colour_.resize(size_t(e.count));
  const bool in_blocks = read_in_blocks(body, e.count, [&](PlyBody& block, uint64_t first, uint64_t end) {
    VertexEntry vertex;
    for (uint64_t i = first; i < end; ++i) {
      read_vertex(block, e, vertex);
      keep_vertex(size_t(i), vertex);
    }
    return block.position();
  });
  if (in_blocks) return;
  VertexEntry vertex;
  for (uint64_t i = 0; i < e.count; ++i) {
    body.at(e.name, i);
    read_vertex(body, e, vertex);
    keep_vertex(size_t(i), vertex);
  }
}

void PlyReader::read_face(PlyBody& body, const PlyElement& e, FaceEntry& face) const {
  face.texnumber = 0;
  face.colour = {0.0f, 0.0f, 0.0f, 1.0f};
  const uint64_t vertices = header_.elements[header_.vertex].count;
  for (const PlyProperty& prop : e.properties) {
    if (prop.role == PlyRole::kVertexIndices) {
      const size_t n = body.list_size(prop.count_type, kMaxCorners, prop.name);
      if (n < 3) body.fail("face has {} corner{} (needs at least 3)", n, n == 1 ? "" : "s");
      face.corners.resize(n);
      for (uint32_t& c : face.corners) {
        const double v = body.value(prop.type);
        if (v < 0 || v >= double(vertices)) body.fail("vertex index {} out of range (the file has {} vertices)", v, vertices);
        c = uint32_t(v);
      }
    } else if (prop.role == PlyRole::kTexcoord) {
      face.texcoord.resize(body.list_size(prop.count_type, 2 * kMaxCorners, prop.name));
      for (double& t : face.texcoord) t = coordinate(body, prop.type, "texture coordinate");
    } else if (prop.role == PlyRole::kTexnumber) {
      const double t = body.value(prop.type);
      const size_t pages = header_.texture_files.size();
      if (t != -1 && !(t >= 0 && t < double(pages) && t == std::floor(t)))
        body.fail("texnumber {} out of range (the header names {} texture file{})", t, pages, pages == 1 ? "" : "s");
      face.texnumber = int32_t(t);
    } else if (prop.role >= PlyRole::kRed && prop.role <= PlyRole::kAlpha) {
      face.colour[size_t(int(prop.role) - int(PlyRole::kRed))] = colour_value(body, prop.type);
    } else {
      body.skip(prop);
    }
  }
  body.end_entry();
}

void PlyReader::add_face(PlyBody& body, const FaceEntry& face, FaceArrays& out) const {
  const size_t n = face.corners.size();
  if (header_.face_texcoord && face.texcoord.size() != 2 * n)
    body.fail("texcoord list of {} values for a face of {} corners (needs {})", face.texcoord.size(), n, 2 * n);
  if (n > 3) ++out.polygons_triangulated;
  const int32_t texture = header_.texture_files.empty() ? -1 : face.texnumber;
  // Fan around the first corner, as the OBJ reader: exact for the convex polygons exporters write.
  for (size_t i = 1; i + 1 < n; ++i) {
    out.triangles.push_back({face.corners[0], face.corners[i], face.corners[i + 1]});
    out.face_texture.push_back(texture);
    if (header_.face_color) out.face_colour.push_back(face.colour);
    if (!header_.face_texcoord) continue;
    for (const size_t k : {size_t(0), i, i + 1}) out.corner_uv.emplace_back(face.texcoord[2 * k], face.texcoord[2 * k + 1]);
  }
}

void PlyReader::read_faces(PlyBody& body, const PlyElement& e) {
  std::vector<FaceArrays> blocks(size_t(e.count / block_entries_ + 1));  // at least one per block
  const bool in_blocks = read_in_blocks(body, e.count, [&](PlyBody& block, uint64_t first, uint64_t end) {
    FaceArrays& out = blocks[size_t(first / block_entries_)];
    FaceEntry face;
    for (uint64_t i = first; i < end; ++i) {
      read_face(block, e, face);
      add_face(block, face, out);
    }
    return block.position();
  });
  if (in_blocks) {
    faces_.reserve_for(blocks);
    for (const FaceArrays& b : blocks) faces_.append(b);
    return;
  }
  // One triangle per face is exact for the triangle meshes scanners write; polygons grow the arrays.
  faces_.triangles.reserve(size_t(e.count));
  faces_.face_texture.reserve(size_t(e.count));
  if (header_.face_texcoord) faces_.corner_uv.reserve(3 * size_t(e.count));
  FaceEntry face;
  for (uint64_t i = 0; i < e.count; ++i) {
    body.at(e.name, i);
    read_face(body, e, face);
    add_face(body, face, faces_);
  }
}

void PlyReader::skip_element(PlyBody& body, const PlyElement& e) {
  if (e.properties.empty()) return;  // takes no bytes, whatever its count
  for (uint64_t i = 0; i < e.count; ++i) {
    body.at(e.name, i);
    for (const PlyProperty& prop : e.properties) body.skip(prop);
  }
}

void PlyReader::assemble_uvs(TexturedMesh& mesh) {
  if (header_.face_texcoord) {
    mesh.corner_uv = std::move(faces_.corner_uv);
    return;
  }
  if (!header_.vertex_uv) {  // a vertex-coloured model: its texture comes from the colours
    mesh.corner_uv.assign(3 * faces_.triangles.size(), Vec2::Zero());
    return;
  }
  // Per-vertex coordinates, copied to each corner (read after the vertices, whatever the order).
  mesh.corner_uv.reserve(3 * faces_.triangles.size());
  for (const Tri& t : faces_.triangles)
    for (const uint32_t v : t) mesh.corner_uv.push_back(vertex_uv_[v]);
}

/// Per corner: the face's colour where faces have one, else the vertex's.
void PlyReader::assemble_colours(TexturedMesh& mesh) {
  if (header_.face_color) {
    mesh.corner_color.reserve(3 * faces_.face_colour.size());
    for (const std::array<float, 4>& c : faces_.face_colour) mesh.corner_color.insert(mesh.corner_color.end(), 3, c);
  } else if (header_.vertex_color) {
    mesh.corner_color.reserve(3 * faces_.triangles.size());
    for (const Tri& t : faces_.triangles)
      for (const uint32_t v : t) mesh.corner_color.push_back(vertex_colour_[v]);
  }
}

void PlyReader::assemble_materials(TexturedMesh& mesh) {
  const fs::path folder = fs::path(path_).parent_path();
  for (const PlyTextureFile& file : header_.texture_files) {
    const std::string written = with_forward_slashes(file.name);
    const NamedFile named = find_named_file(folder, written, options_.allow_outside_files);
    if (!named.refused.empty())
      fail_input("{}:{}: texture '{}' (comment TextureFile) {}", path_, file.line, excerpt(file.name), named.refused);
    const std::optional<fs::path>& found = named.path;
    if (found && *found != folder / written) paths_found_.push_back(fmt::format("{} -> {}", written, found->lexically_normal().string()));
    Material m;
    m.name = fs::path(written).stem().string();
    m.texture = int(mesh.textures.size());
    mesh.materials.push_back(m);
    Texture& t = mesh.textures.emplace_back(Texture{(found ? *found : folder / written).lexically_normal().string(), Image{}});
    t.named_at = fmt::format("{}:{}: texture '{}' (comment TextureFile)", path_, file.line, excerpt(file.name));
  }
  if (options_.load_textures) mesh.textures = load_texture_pixels(mesh, options_.max_texture_pixels);
}

TexturedMesh PlyReader::read(ModelReadStats* stats) {
  std::string data;
  std::string reason;
  if (!read_whole_file(path_, data, reason)) fail_input("{}: {}", path_, reason);
  header_ = parse_ply_header(path_, data);
  if (!header_.face_texcoord && !header_.vertex_uv && !header_.vertex_color && !header_.face_color)
    fail_input(
        "{}: model has neither texture coordinates (face texcoord, or vertex s t / u v / texture_u texture_v) nor colours (red green "
        "blue); tightex needs the input's UV atlas or its vertex colours",
        path_);
  PlyBody body(path_, std::string_view(data).substr(header_.body_offset), header_.format, header_.lines);
  for (size_t i = 0; i < header_.elements.size(); ++i) {
    const PlyElement& e = header_.elements[i];
    if (i == header_.vertex)
      read_vertices(body, e);
    else if (i == header_.face)
      read_faces(body, e);
    else
      skip_element(body, e);
  }
  if (faces_.triangles.empty()) fail_input("{}: no faces", path_);

  TexturedMesh mesh;
  mesh.source = path_;
  mesh.positions = std::move(positions_);
  assemble_uvs(mesh);
  assemble_colours(mesh);
  mesh.triangles = std::move(faces_.triangles);
  mesh.face_material = std::move(faces_.face_texture);
  assemble_materials(mesh);
  if (stats != nullptr) {
    stats->polygons_triangulated = faces_.polygons_triangulated;
    stats->lines = header_.lines + body.lines_read(header_.lines);
    stats->paths_found = paths_found_;
  }
  return mesh;
}

}  // namespace

TexturedMesh read_ply_in_blocks(const std::string& path, const ModelReadOptions& options, ModelReadStats* stats, uint64_t block_entries) {
  return PlyReader(path, options, block_entries).read(stats);
}

TexturedMesh read_ply(const std::string& path, const ModelReadOptions& options, ModelReadStats* stats) {
  return read_ply_in_blocks(path, options, stats, kPlyBlockEntries);
}

}  // namespace tightex
