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
constexpr uint32_t kVersion = 1;
constexpr size_t kHeader = 64;

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

std::string serialize_lot(const OctreeTexture& t) {
  const auto pool = t.words();
  std::vector<std::pair<uint32_t, uint32_t>> frees;
  // The free lists in their own order: a load must allocate exactly as the saved texture would.
  const auto& lists = OctreeEditor::free_lists(t);
  for (size_t k = 0; k < lists.size(); ++k)
    for (uint32_t p : lists[k]) frees.push_back({uint32_t(k), p});
  std::string payload;
  payload.reserve(4 * pool.size() + 8 * frees.size());
  for (uint32_t w : pool) put32(payload, w);
  for (auto [n, p] : frees) put32(payload, n), put32(payload, p);

  std::string out(reinterpret_cast<const char*>(kMagic), 8);
  put32(out, kVersion);
  put32(out, uint32_t(kHeader));
  put32(out, 0);
  for (int k = 0; k < 3; ++k) putf(out, t.origin()[k]);
  putf(out, t.size());
  put32(out, t.background());
  put64(out, pool.size());
  put64(out, frees.size());
  put32(out, crc32(payload));
  put32(out, crc32(out));
  out += payload;
  return out;
}

OctreeTexture parse_lot(std::string_view bytes, std::string_view name, bool verify_checksums) {
  const std::string who(name);
  auto fail = [&](const std::string& why) -> void { throw InputError(who + ": " + why); };
  if (bytes.empty()) fail("empty file");
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kMagic, 8) != 0)
    fail("not a limn octree texture (.lot): wrong magic bytes");
  if (bytes.size() < kHeader)
    fail("truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the 64-byte header");
  const uint32_t version = get32(bytes, 8);
  if (version != kVersion)
    fail("unsupported .lot version " + std::to_string(version) + " (this limn reads version 1)");
  if (verify_checksums && crc32(bytes.substr(0, 60)) != get32(bytes, 60))
    fail("corrupt: header checksum mismatch");
  if (get32(bytes, 12) != kHeader) fail("corrupt: header size is not 64");
  if (get32(bytes, 16) != 0) fail("unsupported flags " + std::to_string(get32(bytes, 16)));
  const uint64_t words = get64(bytes, 40), frees = get64(bytes, 48);
  const uint64_t avail = bytes.size() - kHeader;
  if (words > avail / 4 || frees > (avail - 4 * words) / 8)
    fail("truncated: the header promises " + std::to_string(words) + " pool words and " +
         std::to_string(frees) + " free blocks, more than the file's " +
         std::to_string(bytes.size()) + " bytes hold");
  const uint64_t expect = kHeader + 4 * words + 8 * frees;
  if (expect != bytes.size())
    fail("corrupt: " + std::to_string(bytes.size() - expect) + " bytes of trailing data");
  if (verify_checksums && crc32(bytes.substr(kHeader)) != get32(bytes, 56))
    fail("corrupt: payload checksum mismatch");
  float origin[3];
  for (int k = 0; k < 3; ++k) origin[k] = getf(bytes, 20 + 4 * size_t(k));
  const float size = getf(bytes, 32);
  if (!(std::isfinite(origin[0]) && std::isfinite(origin[1]) && std::isfinite(origin[2]) &&
        std::isfinite(size) && size > 0))
    fail("corrupt: the texture cube is not finite with a positive size");
  if (words < 2 || words > octree::kMaxPoolWords + 2)
    fail("corrupt: " + std::to_string(words) + " pool words");
  OctreeTexture t = OctreeTexture::empty(origin, size, get32(bytes, 36));
  auto& pool = OctreeEditor::pool(t);
  pool.resize(size_t(words));
  for (size_t i = 0; i < pool.size(); ++i) pool[i] = get32(bytes, kHeader + 4 * i);
  auto& lists = OctreeEditor::free_lists(t);
  size_t at = kHeader + 4 * size_t(words);
  for (uint64_t i = 0; i < frees; ++i, at += 8) {
    const uint32_t n = get32(bytes, at), p = get32(bytes, at + 4);
    // No block limn writes is longer than a full brick (141 words).
    if (n < 2 || n > 512)
      fail("corrupt: free block " + std::to_string(i) + " has class " + std::to_string(n));
    if (lists.size() <= n) lists.resize(n + 1);
    lists[n].push_back(p);
  }
  const std::string problem = t.check();
  if (!problem.empty()) fail("corrupt: " + problem);
  return t;
}

void save_lot(const OctreeTexture& t, const std::filesystem::path& path) {
  write_file_atomic(path, serialize_lot(t));
}

OctreeTexture load_lot(const std::filesystem::path& path) {
  const std::string data = read_file(path);
  return parse_lot(data, path.string());
}

}  // namespace limn
