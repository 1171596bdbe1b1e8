// The .lot file: header, checksums, payload, and a parser that trusts nothing it reads.
#include <array>
#include <cmath>
#include <cstring>
#include <string>

#include "limn/mesh/file.hpp"
#include "limn/paint/file.hpp"
#include "octree_blocks.hpp"

namespace limn {

using detail::OctreeEditor;

namespace {

constexpr unsigned char kMagic[8] = {0x89, 'L', 'O', 'T', 0x0D, 0x0A, 0x1A, 0x0A};
constexpr uint32_t kVersion = 2;
constexpr size_t kHeader = 96, kHeaderV1 = 64;
constexpr uint32_t kFlagRmh = 1;

const std::array<uint32_t, 256>& crc_table() {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  return table;
}

void put32(std::string& s, uint32_t v) {
  for (int k = 0; k < 4; ++k) s.push_back(char(v >> (8 * k) & 255u));
}
void put64(std::string& s, uint64_t v) {
  for (int k = 0; k < 8; ++k) s.push_back(char(v >> (8 * k) & 255u));
}
void putf(std::string& s, float f) {
  uint32_t v;
  std::memcpy(&v, &f, 4);
  put32(s, v);
}
uint32_t get32(std::string_view s, size_t at) {
  uint32_t v = 0;
  for (int k = 0; k < 4; ++k)
    v |= uint32_t(static_cast<unsigned char>(s[at + size_t(k)])) << (8 * k);
  return v;
}
uint64_t get64(std::string_view s, size_t at) {
  return uint64_t(get32(s, at)) | uint64_t(get32(s, at + 4)) << 32;
}
float getf(std::string_view s, size_t at) {
  const uint32_t v = get32(s, at);
  float f;
  std::memcpy(&f, &v, 4);
  return f;
}

}  // namespace

uint32_t crc32(std::string_view bytes, uint32_t crc) {
  const auto& t = crc_table();
  uint32_t c = ~crc;
  for (char ch : bytes) c = t[(c ^ static_cast<unsigned char>(ch)) & 255u] ^ (c >> 8);
  return ~c;
}

namespace {

// A texture's payload: its pool words, then its free lists as (class, block) pairs.
std::string payload_of(const OctreeTexture& t, uint64_t& words, uint64_t& frees) {
  const auto pool = t.words();
  std::string payload;
  // The free lists in their own order: a load must allocate exactly as the saved texture would.
  const auto& lists = OctreeEditor::free_lists(t);
  frees = 0;
  for (const auto& l : lists) frees += l.size();
  payload.reserve(4 * pool.size() + 8 * frees);
  for (uint32_t w : pool) put32(payload, w);
  for (size_t k = 0; k < lists.size(); ++k)
    for (uint32_t p : lists[k]) put32(payload, uint32_t(k)), put32(payload, p);
  words = pool.size();
  return payload;
}

std::string serialize(const OctreeTexture& color, const OctreeTexture* rmh, float height_scale) {
  uint64_t words = 0, frees = 0, rmh_words = 0, rmh_frees = 0;
  const std::string payload = payload_of(color, words, frees);
  const std::string rmh_payload = rmh ? payload_of(*rmh, rmh_words, rmh_frees) : std::string();
  std::string out(reinterpret_cast<const char*>(kMagic), 8);
  put32(out, kVersion);
  put32(out, uint32_t(kHeader));
  put32(out, rmh ? kFlagRmh : 0);
  for (int k = 0; k < 3; ++k) putf(out, color.origin()[k]);
  putf(out, color.size());
  put32(out, color.background());
  put64(out, words);
  put64(out, frees);
  put32(out, crc32(payload));
  putf(out, height_scale);
  put32(out, rmh ? rmh->background() : 0);
  put32(out, 0);
  put64(out, rmh_words);
  put64(out, rmh_frees);
  put32(out, crc32(rmh_payload));
  put32(out, crc32(out));
  out += payload;
  out += rmh_payload;
  return out;
}

// Builds a texture from a payload at `at` and checks its structure.
OctreeTexture texture_from(std::string_view bytes, size_t at, uint64_t words, uint64_t frees,
                           const float origin[3], float size, Rgba8 background,
                           const std::string& who, const char* what) {
  auto fail = [&](const std::string& why) -> void {
    throw InputError(who + ": corrupt: " + what + why);
  };
  if (words < 2 || words > octree::kMaxPoolWords + 2) fail(std::to_string(words) + " pool words");
  OctreeTexture t = OctreeTexture::empty(origin, size, background);
  auto& pool = OctreeEditor::pool(t);
  pool.resize(size_t(words));
  for (size_t i = 0; i < pool.size(); ++i) pool[i] = get32(bytes, at + 4 * i);
  auto& lists = OctreeEditor::free_lists(t);
  at += 4 * size_t(words);
  for (uint64_t i = 0; i < frees; ++i, at += 8) {
    const uint32_t n = get32(bytes, at), p = get32(bytes, at + 4);
    // No block limn writes is longer than a full brick (141 words).
    if (n < 2 || n > 512)
      fail("free block " + std::to_string(i) + " has class " + std::to_string(n));
    if (lists.size() <= n) lists.resize(n + 1);
    lists[n].push_back(p);
  }
  const std::string problem = t.check();
  if (!problem.empty()) fail(problem);
  return t;
}

}  // namespace

std::string serialize_lot(const MaterialTexture& m) {
  return serialize(m.color, m.rmh ? &*m.rmh : nullptr, m.height_scale);
}

std::string serialize_lot(const OctreeTexture& t) {
  return serialize(t, nullptr, kDefaultHeightScale * t.size());
}

MaterialTexture parse_lot(std::string_view bytes, std::string_view name, bool verify_checksums) {
  const std::string who(name);
  auto fail = [&](const std::string& why) -> void { throw InputError(who + ": " + why); };
  if (bytes.empty()) fail("empty file");
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kMagic, 8) != 0)
    fail("not a limn octree texture (.lot): wrong magic bytes");
  if (bytes.size() < kHeaderV1)
    fail("truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the 64-byte header");
  const uint32_t version = get32(bytes, 8);
  if (version != 1 && version != 2)
    fail("unsupported .lot version " + std::to_string(version) +
         " (this limn reads versions 1 and 2)");
  const size_t header = version == 1 ? kHeaderV1 : kHeader;
  if (bytes.size() < header)
    fail("truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the " +
         std::to_string(header) + "-byte header");
  if (verify_checksums && crc32(bytes.substr(0, header - 4)) != get32(bytes, header - 4))
    fail("corrupt: header checksum mismatch");
  if (get32(bytes, 12) != header) fail("corrupt: header size is not " + std::to_string(header));
  const uint32_t flags = get32(bytes, 16);
  if (flags & ~(version == 1 ? 0u : kFlagRmh)) fail("unsupported flags " + std::to_string(flags));
  const bool has_rmh = flags & kFlagRmh;
  const uint64_t words = get64(bytes, 40), frees = get64(bytes, 48);
  const uint64_t rmh_words = version == 1 ? 0 : get64(bytes, 72);
  const uint64_t rmh_frees = version == 1 ? 0 : get64(bytes, 80);
  if (!has_rmh && (rmh_words || rmh_frees)) fail("corrupt: an RMH payload without its flag");
  // Each count checked against what is left before it is multiplied, so nothing overflows.
  uint64_t avail = bytes.size() - header;
  bool fits = true;
  for (auto [n, unit] : {std::pair{words, 4}, {frees, 8}, {rmh_words, 4}, {rmh_frees, 8}}) {
    if (n > avail / uint64_t(unit)) {
      fits = false;
      break;
    }
    avail -= n * uint64_t(unit);
  }
  if (!fits)
    fail("truncated: the header promises " + std::to_string(words + rmh_words) +
         " pool words and " + std::to_string(frees + rmh_frees) +
         " free blocks, more than the file's " + std::to_string(bytes.size()) + " bytes hold");
  if (avail) fail("corrupt: " + std::to_string(avail) + " bytes of trailing data");
  const size_t rmh_at = header + 4 * size_t(words) + 8 * size_t(frees);
  if (verify_checksums && crc32(bytes.substr(header, rmh_at - header)) != get32(bytes, 56))
    fail("corrupt: payload checksum mismatch");
  if (verify_checksums && version == 2 && crc32(bytes.substr(rmh_at)) != get32(bytes, 88))
    fail("corrupt: RMH payload checksum mismatch");
  float origin[3];
  for (int k = 0; k < 3; ++k) origin[k] = getf(bytes, 20 + 4 * size_t(k));
  const float size = getf(bytes, 32);
  if (!(std::isfinite(origin[0]) && std::isfinite(origin[1]) && std::isfinite(origin[2]) &&
        std::isfinite(size) && size > 0))
    fail("corrupt: the texture cube is not finite with a positive size");
  MaterialTexture m;
  m.height_scale = version == 1 ? kDefaultHeightScale * size : getf(bytes, 60);
  if (!(std::isfinite(m.height_scale) && m.height_scale > 0))
    fail("corrupt: the height scale is not a positive number");
  m.color = texture_from(bytes, header, words, frees, origin, size, get32(bytes, 36), who, "");
  if (has_rmh)
    m.rmh = texture_from(bytes, rmh_at, rmh_words, rmh_frees, origin, size, get32(bytes, 64), who,
                         "RMH texture: ");
  return m;
}

void save_lot(const MaterialTexture& m, const std::filesystem::path& path) {
  write_file_atomic(path, serialize_lot(m));
}

void save_lot(const OctreeTexture& t, const std::filesystem::path& path) {
  write_file_atomic(path, serialize_lot(t));
}

MaterialTexture load_lot(const std::filesystem::path& path) {
  const std::string data = read_file(path);
  return parse_lot(data, path.string());
}

}  // namespace limn
