// What the model readers (OBJ, PLY) share: reading a whole file, finding the files a model names as
// its exporter meant them, loading the textures, and quoting input text in a one-line message.
#pragma once
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tightex/mesh.hpp"

namespace tightex {

/// Beyond this a coordinate is an exporter bug (uninitialised memory, a unit mistake of many orders of
/// magnitude), and squaring it in any later area or length computation would overflow or lose all
/// precision: every reader refuses it.
constexpr double kAbsurdCoordinate = 1e15;

/// The blanks that separate words in OBJ, MTL and PLY header text.
constexpr bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

/// Input text quoted in a message: at most 60 characters, unprintable ones as '?', so a binary file
/// handed in as a model cannot turn an error into a screenful of garbage or break the one-line message.
std::string excerpt(std::string_view s);

bool equals_ignoring_case(std::string_view a, std::string_view b);

/// Paths written on Windows use backslashes; on every platform tightex runs on '/' works.
std::string with_forward_slashes(std::string_view s);

/// What find_named_file gives: the file, or nothing (not found, or refused: `refused` says why).
struct NamedFile {
  std::optional<std::filesystem::path> path;
  /// Non-empty where the reference leads out of the folder and the rule refuses it: why, as a phrase
  /// that follows the reference in a message ("is an absolute path out of the folder /a/b (...)").
  std::string refused;
};

/// The file a model names, as the exporter meant it: `written` (forward slashes) under `folder`, else
/// the same path matched without case (exported on Windows or macOS, where TEXTURE.JPG and texture.jpg
/// are one file), else the longest tail of it that exists under `folder` that way (an absolute path of
/// the machine that wrote it, "C:/Users/me/scan/textures/tex_0.jpg", or "../textures/tex_0.jpg" after
/// the files were moved). One pair of surrounding double quotes is dropped.
/// The rule for untrusted input (docs/architecture.md, "Files a model names"): unless `allow_outside`,
/// the file must lie inside `folder` once `..` is resolved and symbolic links are followed; an
/// absolute path, a `..` that escapes or a symbolic link leading out that names an existing file
/// outside is refused, a `file:` URI always; no folder outside is listed and no file outside opened.
/// With `allow_outside`, `written` may name any file (a file: URI its path).
NamedFile find_named_file(const std::filesystem::path& folder, std::string written, bool allow_outside);

/// Page faults on freshly allocated buffers can cost more than the parsing that fills them
/// (docs/decisions.md), so large buffers a reader is about to fill are mapped in one call. Only whole
/// pages inside the buffer are touched, and populating never changes memory contents; on kernels
/// without MADV_POPULATE_WRITE (before 5.14) this does nothing.
void prefault_for_write(void* start, size_t bytes);

/// A file that a model names (material library, texture) must be a regular file: a device or FIFO named
/// by a hostile model would otherwise be read until memory runs out (/dev/zero) or block forever (a FIFO
/// with no writer). Only the model given on the command line may be a pipe.
inline constexpr const char* kNotRegular = "is not a regular file (a device, pipe or socket)";

/// True for a device, pipe or socket.
bool is_special_file(const std::filesystem::file_status& status);

/// Reads a whole file. On failure returns false and a reason that reads after the file name
/// ("not found", "is a directory, not a file", ...). `regular_only`: refuse devices, pipes and sockets.
bool read_whole_file(const std::filesystem::path& path, std::string& data, std::string& reason, bool regular_only = false);

/// Parses a whole token as a double (a leading '+' allowed). "nan" and "inf" parse (the caller refuses
/// them with a clearer message than "malformed"); a number beyond double's range parses as ±infinity.
bool parse_double(std::string_view token, double& out);

/// Decodes the image of every texture that has no pixels yet from its path (in parallel; a device or
/// pipe is refused); one made from vertex colours, or decoded already, stays as it is. Returns one
/// message per texture: empty where it loaded (or was left), else load_image's reason on one line, so
/// the caller can report the first failure in the model's order, whatever the thread timing.
std::vector<std::string> load_texture_images(std::vector<Texture>& textures, size_t max_pixels);

}  // namespace tightex
