// limn mesh: whole-file reads and atomic writes, which every layer's files use (meshes,
// textures, stroke scripts, images).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace limn {

/// Writes bytes to `path` atomically: a temporary file beside it, flushed, then renamed over it.
/// Throws std::runtime_error naming the path on failure; the old file is then untouched.
/// O(bytes).
void write_file_atomic(const std::filesystem::path& path, std::string_view bytes);

/// Reads a whole file (at most 16 GB). Throws InputError for missing, unreadable, oversized or
/// directory paths. O(file size).
std::string read_file(const std::filesystem::path& path);

}  // namespace limn
