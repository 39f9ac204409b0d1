// What the model readers share: whole files, the files a model names, texture loading, excerpts.
#include "io/model_files.hpp"

#include <sys/mman.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "core/error.hpp"
#include "io/image_io.hpp"

namespace tightex {

namespace fs = std::filesystem;

std::string excerpt(std::string_view s) {
  constexpr size_t kMaxChars = 60;
  std::string out;
  for (size_t i = 0; i < s.size() && i < kMaxChars; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    out += (c >= 0x20 && c != 0x7f) ? char(c) : '?';
  }
  if (s.size() > kMaxChars) out += "...";
  return out;
}

bool equals_ignoring_case(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    const char x = (a[i] >= 'A' && a[i] <= 'Z') ? char(a[i] - 'A' + 'a') : a[i];
    const char y = (b[i] >= 'A' && b[i] <= 'Z') ? char(b[i] - 'A' + 'a') : b[i];
    if (x != y) return false;
  }
  return true;
}

std::string with_forward_slashes(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    if (c == '\\') c = '/';
  return out;
}

namespace {

/// Whether `written` begins with "file:", without case.
bool is_file_uri(std::string_view written) { return written.size() >= 5 && equals_ignoring_case(written.substr(0, 5), "file:"); }

/// The path a file: URI names ("file:///a/b", "file://host/a/b", "file:/a/b" -> "/a/b").
std::string path_of_file_uri(std::string_view uri) {
  std::string_view rest = uri.substr(5);
  if (rest.substr(0, 2) == "//") {
    rest.remove_prefix(2);
    const size_t slash = rest.find('/');
    rest = slash == std::string_view::npos ? std::string_view() : rest.substr(slash);
  }
  return std::string(rest);
}

/// Whether `written` starts with a Windows drive ("C:/", "C:"), which is a component of its own on
/// this platform.
bool has_windows_drive(std::string_view written) {
  const bool letter = !written.empty() && ((written[0] >= 'A' && written[0] <= 'Z') || (written[0] >= 'a' && written[0] <= 'z'));
  return letter && written.size() >= 2 && written[1] == ':' && (written.size() == 2 || written[2] == '/');
}

/// Whether `path` (following its symbolic links) lies in the folder `root` (canonical already).
bool lies_in(const fs::path& path, const fs::path& root) {
  std::error_code ec;
  const fs::path real = fs::weakly_canonical(path, ec);
  if (ec) return false;
  const fs::path rel = real.lexically_relative(root);
  return !rel.empty() && *rel.begin() != "..";
}

/// The search of find_named_file: `parts` (no "..") matched under `folder`, each component as written
/// or without case. `root`: where the rule keeps the search (no folder listed outside it); empty: anywhere.
std::optional<fs::path> find_without_case(const fs::path& folder, const std::vector<std::string>& parts, const fs::path& root) {
  std::error_code ec;
  fs::path at = folder;
  for (const std::string& part : parts) {
    if (part == ".") continue;
    if (part == "..") {
      at /= part;
      continue;
    }
    if (fs::exists(at / part, ec)) {
      at /= part;
      continue;
    }
    // One directory listing per component (directories of scans hold few files; a folder that cannot
    // be listed ends the search).
    if (!root.empty() && !lies_in(at, root)) return std::nullopt;
    std::optional<fs::path> match;
    for (fs::directory_iterator it(at, ec), end; !ec && it != end; it.increment(ec))
      if (equals_ignoring_case(it->path().filename().string(), part)) {
        if (match) return std::nullopt;  // two names differ only in case: ambiguous
        match = it->path();
      }
    if (!match) return std::nullopt;
    at = *match;
  }
  return at;
}

/// `folder` / `exact` where it exists (`exact` empty: not tried), else the longest tail of `written`
/// found without case under `folder` (a Windows drive, "C:", is never part of a tail).
std::optional<fs::path> search_named_file(const fs::path& folder, const fs::path& exact, const fs::path& written, const fs::path& root) {
  std::error_code ec;
  if (!exact.empty() && fs::exists(folder / exact, ec)) return folder / exact;
  std::vector<std::string> parts;
  for (const auto& part : written.relative_path()) parts.push_back(part.string());
  const bool absolute = written.has_root_directory() || has_windows_drive(written.string());
  for (size_t first = 0; first < parts.size(); ++first) {
    if (first == 0 && absolute) continue;
    if (parts[first] == ".." || parts[first] == ".") continue;
    const std::vector<std::string> tail(parts.begin() + long(first), parts.end());
    if (auto found = find_without_case(folder, tail, root); found && fs::is_regular_file(*found, ec)) return found;
  }
  return std::nullopt;
}

}  // namespace

NamedFile find_named_file(const fs::path& folder, std::string written, bool allow_outside) {
  if (written.size() >= 2 && written.front() == '"' && written.back() == '"') written = written.substr(1, written.size() - 2);
  if (written.empty()) return {};
  constexpr const char* kLift = " (--allow-outside-files reads it)";
  if (allow_outside) {
    if (is_file_uri(written)) written = path_of_file_uri(written);
    return {search_named_file(folder, written, written, {}), {}};
  }
  if (is_file_uri(written)) return {std::nullopt, std::string("is a file: URI, which may name any file on this machine") + kLift};
  std::error_code ec;
  const fs::path root = fs::weakly_canonical(folder.empty() ? fs::path(".") : folder, ec);
  const fs::path normal = fs::path(written).lexically_normal();
  const bool absolute = normal.has_root_directory() || has_windows_drive(written);
  const bool escapes = !absolute && !normal.empty() && *normal.begin() == "..";
  // An absolute path into the folder is read as written; any other absolute or escaping reference is
  // looked for only inside the folder, by a tail of it (a Windows exporter's "C:/Users/me/scan/tex.jpg",
  // "../textures/tex.jpg" after the files were moved).
  const bool as_written = absolute ? normal.has_root_directory() && lies_in(normal, root) : !escapes;
  const std::optional<fs::path> found = search_named_file(folder, as_written ? fs::path(written) : fs::path(), normal, root);
  if (found) {
    if (lies_in(*found, root)) return {found, {}};
    return {std::nullopt, fmt::format("is a symbolic link that leads out of the folder {}{}", root.string(), kLift)};
  }
  // Not inside the folder: refused only where the file it names exists (else it is just missing).
  if (!absolute && !escapes) return {};
  if (!fs::exists(folder / normal, ec)) return {};
  return {std::nullopt, fmt::format("{} out of the folder {}{}", absolute ? "is an absolute path" : "leads ('..')", root.string(), kLift)};
}

void prefault_for_write(void* start, size_t bytes) {
#if defined(MADV_POPULATE_WRITE)
  constexpr size_t kWorthIt = size_t(256) << 10;
  if (bytes < kWorthIt) return;
  const auto page = uintptr_t(sysconf(_SC_PAGESIZE));
  const uintptr_t begin = (uintptr_t(start) + page - 1) & ~(page - 1);
  const uintptr_t end = (uintptr_t(start) + bytes) & ~(page - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_POPULATE_WRITE);
#else
  (void)start;
  (void)bytes;
#endif
}

bool is_special_file(const fs::file_status& status) {
  return fs::exists(status) && !fs::is_regular_file(status) && !fs::is_directory(status);
}

bool read_whole_file(const fs::path& path, std::string& data, std::string& reason, bool regular_only) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (status.type() == fs::file_type::not_found) {
    reason = "not found";
    return false;
  }
  if (ec) {
    reason = fmt::format("cannot be accessed ({})", ec.message());
    return false;
  }
  if (fs::is_directory(status)) {
    reason = "is a directory, not a file";
    return false;
  }
  if (regular_only && is_special_file(status)) {
    reason = kNotRegular;
    return false;
  }
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) {
    reason = fmt::format("cannot be opened ({})", std::strerror(errno));
    return false;
  }
  data.clear();
  const uintmax_t size = fs::is_regular_file(status) ? fs::file_size(path, ec) : 0;
  if (!ec && size > 0) {
    data.reserve(size_t(size));
    prefault_for_write(data.data(), size_t(size));
    data.resize(size_t(size));
    data.resize(std::fread(data.data(), 1, size_t(size), file));
  }
  // Whatever follows comes in chunks: all of a pipe, which has no size, or the end of a file that
  // grew since its size was taken.
  char chunk[1 << 16];
  for (;;) {
    const size_t got = std::fread(chunk, 1, sizeof chunk, file);
    data.append(chunk, got);
    if (got < sizeof chunk) break;
  }
  const bool failed = std::ferror(file) != 0;
  std::fclose(file);
  if (failed) {
    reason = "could not be read (I/O error)";
    return false;
  }
  return true;
}

bool parse_double(std::string_view token, double& out) {
  const char* b = token.data();
  const char* e = b + token.size();
  // from_chars refuses a leading '+', which some exporters write.
  if (b != e && *b == '+') {
    ++b;
    if (b != e && *b == '-') return false;
  }
  if (b == e) return false;
  const auto [ptr, ec] = std::from_chars(b, e, out);
  if (ptr != e) return false;
  if (ec == std::errc::result_out_of_range) {
    // A well-formed number beyond double's range: strtod tells overflow (±HUGE_VAL, refused later as
    // infinite) from underflow (a value that rounds to 0, which is fine).
    const std::string copy(b, e);
    out = std::strtod(copy.c_str(), nullptr);
    return true;
  }
  return ec == std::errc();
}

std::vector<std::string> load_texture_images(std::vector<Texture>& textures, size_t max_pixels) {
  // Decoding an 8K PNG takes a fraction of a second; multi-page atlases decode in parallel.
  std::vector<std::string> errors(textures.size());
  tbb::parallel_for(size_t(0), textures.size(), [&](size_t i) {
    if (!textures[i].image.empty() || textures[i].from_vertex_colours) return;
    try {
      std::error_code ec;
      if (is_special_file(fs::status(textures[i].path, ec))) fail_input("{}: {}", textures[i].path, kNotRegular);
      textures[i].image = load_image(textures[i].path, max_pixels);
    } catch (const InputError& e) {
      errors[i] = e.what();
      // The report is one line; a decoder's message must not break it.
      for (char& c : errors[i])
        if (c == '\n' || c == '\r') c = ' ';
    }
  });
  return errors;
}

}  // namespace tightex
