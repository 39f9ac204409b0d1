// The PLY header: lines of text up to end_header, whatever the body's format.
#include "io/ply_header.hpp"

#include <array>
#include <charconv>
#include <cstring>
#include <utility>

#include "core/error.hpp"
#include "io/model_files.hpp"

namespace tightex {
namespace {

// More texture pages than any scan has; a bound so a hostile header cannot make the reader look up
// millions of files.
constexpr size_t kMaxTextureFiles = 4096;

struct TypeName {
  std::string_view name;
  PlyType type;
};

// Both spellings of the specification: the original names and the sized ones.
constexpr std::array<TypeName, 16> kTypeNames{{{"char", PlyType::kInt8},
                                               {"uchar", PlyType::kUint8},
                                               {"short", PlyType::kInt16},
                                               {"ushort", PlyType::kUint16},
                                               {"int", PlyType::kInt32},
                                               {"uint", PlyType::kUint32},
                                               {"float", PlyType::kFloat32},
                                               {"double", PlyType::kFloat64},
                                               {"int8", PlyType::kInt8},
                                               {"uint8", PlyType::kUint8},
                                               {"int16", PlyType::kInt16},
                                               {"uint16", PlyType::kUint16},
                                               {"int32", PlyType::kInt32},
                                               {"uint32", PlyType::kUint32},
                                               {"float32", PlyType::kFloat32},
                                               {"float64", PlyType::kFloat64}}};

/// Blank-separated words of one header line.
class Words {
 public:
  explicit Words(std::string_view line) : rest_(line) {}
  std::string_view next() {
    while (!rest_.empty() && is_blank(rest_.front())) rest_.remove_prefix(1);
    size_t n = 0;
    while (n < rest_.size() && !is_blank(rest_[n])) ++n;
    const std::string_view word = rest_.substr(0, n);
    rest_.remove_prefix(n);
    return word;
  }
  /// The rest of the line without surrounding blanks (a file name may contain spaces).
  std::string_view rest() {
    while (!rest_.empty() && is_blank(rest_.front())) rest_.remove_prefix(1);
    while (!rest_.empty() && is_blank(rest_.back())) rest_.remove_suffix(1);
    return rest_;
  }

 private:
  std::string_view rest_;
};

class HeaderParser {
 public:
  HeaderParser(const std::string& file, std::string_view data) : file_(file), data_(data) {}
  PlyHeader parse();

 private:
  template <typename... Args>
  [[noreturn]] void fail_here(fmt::format_string<Args...> f, Args&&... args) const {
    fail_input("{}:{}: {}", file_, line_, fmt::format(f, std::forward<Args>(args)...));
  }
  bool next_line(std::string_view& line);
  void parse_line(std::string_view line);
  void parse_format(Words& words);
  void parse_comment(Words& words);
  void parse_element(Words& words);
  void parse_property(Words& words);
  PlyType parse_type(std::string_view word);

  const std::string& file_;
  std::string_view data_;
  size_t at_ = 0;    // next unread byte
  size_t line_ = 0;  // current line, 1-based
  bool saw_format_ = false;
  bool ended_ = false;
  PlyHeader header_;
};

bool HeaderParser::next_line(std::string_view& line) {
  if (at_ >= data_.size()) return false;
  const auto* start = data_.data() + at_;
  const auto* nl = static_cast<const char*>(std::memchr(start, '\n', data_.size() - at_));
  const size_t length = nl != nullptr ? size_t(nl - start) : data_.size() - at_;
  line = std::string_view(start, length);
  at_ += length + (nl != nullptr ? 1 : 0);
  ++line_;
  return true;
}

PlyType HeaderParser::parse_type(std::string_view word) {
  for (const TypeName& t : kTypeNames)
    if (t.name == word) return t.type;
  if (word.empty()) fail_here("property without a type");
  fail_here("unknown property type '{}'", excerpt(word));
}

void HeaderParser::parse_format(Words& words) {
  if (saw_format_) fail_here("second format line");
  saw_format_ = true;
  const std::string_view format = words.next();
  if (format == "ascii")
    header_.format = PlyFormat::kAscii;
  else if (format == "binary_little_endian")
    header_.format = PlyFormat::kBinaryLittleEndian;
  else if (format == "binary_big_endian")
    header_.format = PlyFormat::kBinaryBigEndian;
  else
    fail_here("unknown format '{}' (ascii, binary_little_endian or binary_big_endian)", excerpt(format));
  if (words.next().empty()) fail_here("format line without a version");
}

void HeaderParser::parse_comment(Words& words) {
  // OpenMVS, MeshLab and others name each texture page in a comment: "comment TextureFile tex_0.png".
  if (!equals_ignoring_case(words.next(), "TextureFile")) return;
  const std::string_view name = words.rest();
  if (name.empty()) fail_here("'comment TextureFile' without a file name");
  if (header_.texture_files.size() == kMaxTextureFiles) fail_here("more than {} TextureFile comments", kMaxTextureFiles);
  header_.texture_files.push_back({std::string(name), line_});
}

void HeaderParser::parse_element(Words& words) {
  const std::string_view name = words.next();
  const std::string_view count = words.next();
  if (name.empty() || count.empty()) fail_here("'element' needs a name and a count");
  for (const PlyElement& e : header_.elements)
    if (e.name == name) fail_here("second element '{}'", excerpt(name));
  uint64_t n = 0;
  const auto [end, ec] = std::from_chars(count.data(), count.data() + count.size(), n);
  if (ec != std::errc() || end != count.data() + count.size())
    fail_here("malformed count '{}' of element '{}'", excerpt(count), excerpt(name));
  if (!words.next().empty()) fail_here("unexpected words after the count of element '{}'", excerpt(name));
  header_.elements.push_back({std::string(name), n, {}, line_});
}

void HeaderParser::parse_property(Words& words) {
  if (header_.elements.empty()) fail_here("property before any element");
  PlyElement& element = header_.elements.back();
  PlyProperty p;
  p.line = line_;
  std::string_view word = words.next();
  if (word == "list") {
    p.is_list = true;
    p.count_type = parse_type(words.next());
    if (!is_integer(p.count_type)) fail_here("list size of type {} (needs an integer type)", type_name(p.count_type));
    word = words.next();
  }
  p.type = parse_type(word);
  const std::string_view name = words.next();
  if (name.empty()) fail_here("property without a name");
  if (!words.next().empty()) fail_here("unexpected words after property '{}'", excerpt(name));
  for (const PlyProperty& q : element.properties)
    if (q.name == name) fail_here("second property '{}' in element '{}'", excerpt(name), excerpt(element.name));
  p.name = std::string(name);
  element.properties.push_back(std::move(p));
}

void HeaderParser::parse_line(std::string_view line) {
  Words words(line);
  const std::string_view keyword = words.next();
  if (keyword.empty()) return;
  if (keyword == "format") return parse_format(words);
  if (keyword == "comment") return parse_comment(words);
  if (keyword == "obj_info") return;
  if (keyword == "element") return parse_element(words);
  if (keyword == "property") return parse_property(words);
  if (keyword == "end_header") {
    ended_ = true;
    return;
  }
  fail_here("unknown header line '{}'", excerpt(line));
}

/// Marks red green blue (and alpha, when present) of an element, as MeshLab and scanners write them
/// (also diffuse_red ...); returns whether all three colours are there. Lists keep the role kSkip.
bool assign_colour_roles(PlyElement& element) {
  constexpr std::string_view kNames[4] = {"red", "green", "blue", "alpha"};
  PlyProperty* found[4] = {nullptr, nullptr, nullptr, nullptr};
  for (PlyProperty& p : element.properties)
    for (int c = 0; c < 4; ++c)
      if (!p.is_list && (p.name == kNames[c] || p.name == fmt::format("diffuse_{}", kNames[c]))) found[c] = &p;
  if (found[0] == nullptr || found[1] == nullptr || found[2] == nullptr) return false;
  for (int c = 0; c < 4; ++c)
    if (found[c] != nullptr) found[c]->role = PlyRole(int(PlyRole::kRed) + c);
  return true;
}

/// Marks x y z and the first complete pair of texture coordinates; a header error when x, y or z is
/// missing or a list.
void assign_vertex_roles(const std::string& file, PlyElement& vertex, PlyHeader& header) {
  PlyProperty* by_name[3] = {nullptr, nullptr, nullptr};
  for (PlyProperty& p : vertex.properties)
    for (int axis = 0; axis < 3; ++axis)
      if (p.name.size() == 1 && p.name[0] == "xyz"[axis]) by_name[axis] = &p;
  for (int axis = 0; axis < 3; ++axis) {
    PlyProperty* p = by_name[axis];
    if (p == nullptr) fail_input("{}:{}: element 'vertex' has no property '{}'", file, vertex.line, "xyz"[axis]);
    if (p->is_list) fail_input("{}:{}: property '{}' of element 'vertex' is a list (needs a number)", file, p->line, p->name);
    p->role = PlyRole(int(PlyRole::kX) + axis);
  }
  // Pairs in the order writers use them; a lone s or u is some other attribute and stays skipped.
  constexpr std::pair<std::string_view, std::string_view> kUvNames[] = {{"s", "t"}, {"u", "v"}, {"texture_u", "texture_v"}};
  for (const auto& [u_name, v_name] : kUvNames) {
    PlyProperty *u = nullptr, *v = nullptr;
    for (PlyProperty& p : vertex.properties) {
      if (p.name == u_name && !p.is_list) u = &p;
      if (p.name == v_name && !p.is_list) v = &p;
    }
    if (u == nullptr || v == nullptr) continue;
    u->role = PlyRole::kU;
    v->role = PlyRole::kV;
    header.vertex_uv = true;
    break;
  }
  header.vertex_color = assign_colour_roles(vertex);
}

/// Marks the vertex index list, texcoord and texnumber; a header error when one has the wrong shape or
/// there is no index list.
void assign_face_roles(const std::string& file, PlyElement& face, PlyHeader& header) {
  const PlyProperty* indices = nullptr;
  for (PlyProperty& p : face.properties) {
    if (p.name == "vertex_indices" || p.name == "vertex_index") {
      if (indices != nullptr) fail_input("{}:{}: element 'face' has two vertex index lists", file, p.line);
      if (!p.is_list || !is_integer(p.type))
        fail_input("{}:{}: property '{}' of element 'face' must be a list of integers", file, p.line, p.name);
      p.role = PlyRole::kVertexIndices;
      indices = &p;
    } else if (p.name == "texcoord") {
      if (!p.is_list) fail_input("{}:{}: property 'texcoord' of element 'face' must be a list", file, p.line);
      p.role = PlyRole::kTexcoord;
      header.face_texcoord = true;
    } else if (p.name == "texnumber") {
      if (p.is_list) fail_input("{}:{}: property 'texnumber' of element 'face' must be a number", file, p.line);
      p.role = PlyRole::kTexnumber;
      header.texnumber = true;
    }
  }
  if (indices == nullptr) fail_input("{}:{}: element 'face' has no vertex_indices list", file, face.line);
  header.face_color = assign_colour_roles(face);
}

/// The fewest bytes one instance of the element can take in the body.
uint64_t min_element_bytes(const PlyElement& e, PlyFormat format) {
  if (format == PlyFormat::kAscii) return e.properties.empty() ? 0 : 2 * e.properties.size() - 1;
  uint64_t bytes = 0;
  for (const PlyProperty& p : e.properties) bytes += p.is_list ? type_size(p.count_type) : type_size(p.type);
  return bytes;
}

/// Refuses counts the body cannot hold: a truncated file, or a header that lies.
void check_counts_against_size(const std::string& file, const PlyHeader& header, size_t body_bytes) {
  uint64_t remaining = body_bytes;
  for (const PlyElement& e : header.elements) {
    const uint64_t each = min_element_bytes(e, header.format);
    if (each == 0) continue;
    if (e.count > remaining / each)
      fail_input("{}:{}: element '{}' declares {} entries, more than the {} bytes after the header can hold (truncated, or a wrong count)",
                 file, e.line, excerpt(e.name), e.count, body_bytes);
    remaining -= e.count * each;
  }
}

PlyHeader HeaderParser::parse() {
  std::string_view line;
  if (!next_line(line) || line.substr(0, 3) != "ply" || !Words(line.substr(3)).next().empty())
    fail_input("{}: not a PLY file (the first line is not 'ply')", file_);
  while (!ended_ && next_line(line)) parse_line(line);
  if (!ended_) fail_input("{}: the header has no end_header line (truncated, or not a PLY file)", file_);
  if (!saw_format_) fail_input("{}: the header has no format line", file_);
  header_.body_offset = at_;
  header_.lines = line_;
  bool saw_vertex = false, saw_face = false;
  for (size_t i = 0; i < header_.elements.size(); ++i) {
    PlyElement& e = header_.elements[i];
    if (e.name == "vertex") {
      assign_vertex_roles(file_, e, header_);
      header_.vertex = i;
      saw_vertex = true;
    } else if (e.name == "face") {
      assign_face_roles(file_, e, header_);
      header_.face = i;
      saw_face = true;
    }
  }
  if (!saw_vertex) fail_input("{}: the header has no 'vertex' element", file_);
  if (!saw_face) fail_input("{}: the header has no 'face' element (a point cloud?); tightex needs triangles", file_);
  check_counts_against_size(file_, header_, data_.size() - at_);
  return std::move(header_);
}

}  // namespace

size_t type_size(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

bool is_integer(PlyType type) { return type != PlyType::kFloat32 && type != PlyType::kFloat64; }

const char* type_name(PlyType type) {
  for (const TypeName& t : kTypeNames)
    if (t.type == type) return t.name.data();
  return "?";
}

PlyHeader parse_ply_header(const std::string& file, std::string_view data) { return HeaderParser(file, data).parse(); }

}  // namespace tightex
