// limn paint: the octree texture file (.lot), versioned and checksummed, written atomically.
//
// Layout (little-endian):
//   0  8  magic 89 'L' 'O' 'T' 0D 0A 1A 0A (PNG-style: catches text-mode transfers)
//   8  4  version (1)
//  12  4  header size in bytes (64)
//  16  4  flags (0)
//  20 12  cube origin, 3 float32
//  32  4  cube size, float32
//  36  4  background colour, RGBA8
//  40  8  pool words W
//  48  8  free blocks F
//  56  4  CRC-32 (IEEE) of the payload
//  60  4  CRC-32 of bytes 0-59
//  64     payload: W uint32 pool words, then F (class, block) uint32 pairs, the free lists in
//         order (class = 2 * words, + 1 for a brick's block)
// The file is exactly 64 + 4 W + 8 F bytes. Loading restores the texture exactly (pool, free
// lists), so save(load(f)) == f.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "limn/paint/texture.hpp"

namespace limn {

/// The file's bytes. O(pool).
std::string serialize_lot(const OctreeTexture& t);

/// Parses a .lot file held in memory; `name` appears in errors. Throws InputError (one line:
/// the name and the problem) for a foreign, truncated, corrupt (checksum) or structurally invalid
/// file (OctreeTexture::check). `verify_checksums` false skips only the CRCs (for fuzzing the
/// structural checks). O(size).
OctreeTexture parse_lot(std::string_view bytes, std::string_view name,
                        bool verify_checksums = true);

/// Writes the texture atomically (a temporary file beside `path`, then a rename): a failed save
/// leaves the previous file untouched. Throws std::runtime_error when it cannot be written.
void save_lot(const OctreeTexture& t, const std::filesystem::path& path);

/// Reads a .lot file. Throws InputError naming the file.
OctreeTexture load_lot(const std::filesystem::path& path);

/// CRC-32 (IEEE 802.3, reflected, as zlib's crc32). O(n).
uint32_t crc32(std::string_view bytes, uint32_t crc = 0);

}  // namespace limn
