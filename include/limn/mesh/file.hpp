// limn mesh: whole-file reads and atomic writes, which every layer's files use (meshes,
// textures, stroke scripts, images).
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <utility>

namespace limn {

/// Writes bytes to `path` atomically: a temporary file beside it, flushed, then renamed over it.
/// Throws std::runtime_error naming the path on failure; the old file is then untouched.
/// O(bytes).
void write_file_atomic(const std::filesystem::path& path, std::string_view bytes);

/// Writes several files, all or none: each is written to its temporary file first, and only
/// when all are written are they renamed into place (a failure before that removes them all and
/// leaves the old files untouched). Throws std::runtime_error naming the path. O(bytes).
void write_files_atomic(std::span<const std::pair<std::filesystem::path, std::string>> files);

/// Reads a whole file (at most 16 GB). Throws InputError for missing, unreadable, oversized or
/// directory paths. O(file size).
std::string read_file(const std::filesystem::path& path);

}  // namespace limn
