// limn paint: the octree texture file (.lot), versioned and checksummed, written atomically. It
// holds a material: the colour texture and, when painted, the RMH texture (material.hpp).
//
// Layout, version 2 (little-endian):
//   0  8  magic 89 'L' 'O' 'T' 0D 0A 1A 0A (PNG-style: catches text-mode transfers)
//   8  4  version (2)
//  12  4  header size in bytes (96)
//  16  4  flags (bit 0: an RMH texture follows the colour texture)
//  20 12  cube origin, 3 float32 (both textures')
//  32  4  cube size, float32
//  36  4  colour background, RGBA8
//  40  8  colour pool words W
//  48  8  colour free blocks F
//  56  4  CRC-32 (IEEE) of the colour payload
//  60  4  height scale, float32 (model units of height 1)
//  64  4  RMH background, RGBA8 (the channels' defaults, alpha 0; 0 without RMH)
//  68  4  reserved (0)
//  72  8  RMH pool words W2 (0 without RMH)
//  80  8  RMH free blocks F2 (0 without RMH)
//  88  4  CRC-32 of the RMH payload
//  92  4  CRC-32 of bytes 0-91
//  96     the colour payload: W uint32 pool words, then F (class, block) uint32 pairs, the free
//         lists in order (class = 2 * words, + 1 for a brick's block); then the RMH payload
//         (W2 words, F2 pairs)
// The file is exactly 96 + 4 (W + W2) + 8 (F + F2) bytes. Version 1 (still read) is a colour
// texture alone: a 64-byte header, bytes 0-59 as above (version 1, flags 0), the CRC of bytes
// 0-59 at 60, then the colour payload; its height scale is the default. Loading restores the
// textures exactly (pools, free lists), so save(load(f)) == f for a version-2 file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "limn/paint/material.hpp"

namespace limn {

/// The file's bytes. O(pool).
std::string serialize_lot(const MaterialTexture& m);
/// The bytes of a colour texture alone (MaterialTexture::from_color). O(pool).
std::string serialize_lot(const OctreeTexture& t);

/// Parses a .lot file held in memory; `name` appears in errors. Throws InputError (one line:
/// the name and the problem) for a foreign, truncated, corrupt (checksum) or structurally invalid
/// file (OctreeTexture::check of each texture). `verify_checksums` false skips only the CRCs
/// (for fuzzing the structural checks). O(size).
MaterialTexture parse_lot(std::string_view bytes, std::string_view name,
                          bool verify_checksums = true);

/// Writes the texture atomically (a temporary file beside `path`, then a rename): a failed save
/// leaves the previous file untouched. Throws std::runtime_error when it cannot be written.
void save_lot(const MaterialTexture& m, const std::filesystem::path& path);
void save_lot(const OctreeTexture& t, const std::filesystem::path& path);

/// Reads a .lot file (version 1 or 2). Throws InputError naming the file.
MaterialTexture load_lot(const std::filesystem::path& path);

/// CRC-32 (IEEE 802.3, reflected, as zlib's crc32). O(n).
uint32_t crc32(std::string_view bytes, uint32_t crc = 0);

}  // namespace limn
