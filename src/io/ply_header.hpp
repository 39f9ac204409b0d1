// The header of a PLY file: its format, its elements with their properties in file order, and the
// texture files its comments name. Parsed and checked before the body is read, so every count is
// weighed against the file's size before anything is allocated for it.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace tightex {

enum class PlyFormat : uint8_t { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

/// The scalar types of PLY (char/int8 ... double/float64).
enum class PlyType : uint8_t { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

size_t type_size(PlyType type);
bool is_integer(PlyType type);
/// The type's name as the PLY specification writes it ("uchar", "float", ...).
const char* type_name(PlyType type);

/// What a property means to tightex; everything else is skipped.
enum class PlyRole : uint8_t { kSkip, kX, kY, kZ, kU, kV, kVertexIndices, kTexcoord, kTexnumber, kRed, kGreen, kBlue, kAlpha };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  // a list's items
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;  // a list's size
  PlyRole role = PlyRole::kSkip;
  size_t line = 0;  // in the header
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
  size_t line = 0;
};

/// A `comment TextureFile <name>` line.
struct PlyTextureFile {
  std::string name;  // as written
  size_t line = 0;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::vector<PlyTextureFile> texture_files;
  size_t body_offset = 0;       // first byte after the end_header line
  size_t lines = 0;             // the header's, end_header included
  size_t vertex = 0, face = 0;  // indices into elements
  bool face_texcoord = false;   // the face element has a texcoord list
  bool vertex_uv = false;       // the vertex element has a pair of texture coordinates
  bool texnumber = false;       // the face element has a texnumber
  bool vertex_color = false;    // the vertex element has red green blue (and maybe alpha)
  bool face_color = false;      // the face element has red green blue (and maybe alpha)
};

/// Parses and checks the header at the start of `data`: the format line, element and property lines
/// with known types, a vertex element with x y z and a face element with a vertex index list, roles
/// assigned, and each element's count weighed against the bytes after the header (an element of n
/// values takes at least 2n - 1 bytes in ascii, its scalars' and list sizes' bytes in binary).
/// Throws InputError "FILE:LINE: problem" (`file` names the file).
PlyHeader parse_ply_header(const std::string& file, std::string_view data);

}  // namespace tightex
