// The octree texture on the GPU: the pool in a storage buffer and OctreeSampler's walk in GLSL
// (shaders/octree.glsl, shared by the drawers' fragment shaders and the lookup compute shader).
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <stdexcept>

#include "gl_util.hpp"
#include "limn/render/texture.hpp"
#include "material_shader.hpp"
#include "shaders.hpp"

namespace limn {

namespace detail {

const std::string& material_glsl() {
  static const std::string source = [] {
    // Identifier by identifier: oct_x -> rmh_x, and the file's other globals renamed alike.
    const std::string in = shaders::octree;
    std::string out;
    auto ident = [](char c, bool first) {
      return std::isalpha(static_cast<unsigned char>(c)) || c == '_' ||
             (!first && std::isdigit(static_cast<unsigned char>(c)));
    };
    for (size_t i = 0; i < in.size();) {
      if (!ident(in[i], true)) {
        out += in[i++];
        continue;
      }
      size_t j = i;
      while (j < in.size() && ident(in[j], false)) ++j;
      const std::string w = in.substr(i, j - i);
      if (w.rfind("oct_", 0) == 0)
        out += "rmh_" + w.substr(4);
      else if (w == "pool" || w == "kD" || w == "kFlag")
        out += "rmh_" + w;
      else if (w == "OctreePool")
        out += "RmhPool";
      else
        out += w;
      i = j;
    }
    const std::string from = "binding = 5", to = "binding = " + std::to_string(kRmhBinding);
    const size_t at = out.find(from);
    if (at == std::string::npos) throw std::logic_error("octree.glsl: no pool binding");
    out.replace(at, from.size(), to);
    return out + shaders::material;
  }();
  return source;
}

}  // namespace detail

struct GpuOctreeTexture::Impl {
  gl::Buffer pool;
  size_t capacity = 0;
  std::vector<uint32_t> shadow;  // what the GPU holds, to send only what changed
  size_t last_words = 0;
  double origin[3] = {0, 0, 0}, scale = 1;
  float size = 1;
  uint32_t background = 0;
  float tags[15 * 3] = {};
  mutable gl::Program lookup;
};

GpuOctreeTexture::GpuOctreeTexture(const OctreeTexture& t) : impl_(std::make_unique<Impl>()) {
  for (int k = 0; k <= octree::kTagCount; ++k) {
    const auto d = octree::tag_direction(k);
    for (int j = 0; j < 3; ++j) impl_->tags[3 * k + j] = d[size_t(j)];
  }
  update(t);
}

GpuOctreeTexture::~GpuOctreeTexture() = default;

void GpuOctreeTexture::update(const OctreeTexture& t) {
  Impl& m = *impl_;
  for (int k = 0; k < 3; ++k) m.origin[k] = t.origin()[k];
  m.size = t.size();
  m.scale = double(1u << octree::kMaxDepth) / double(t.size());
  m.background = t.background();
  const auto words = t.words();
  GLint64 max_bytes = 0;
  glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_bytes);
  if (GLint64(words.size_bytes()) > max_bytes)
    throw std::runtime_error(fmt::format(
        "OpenGL: the octree texture's pool ({} MB) exceeds the driver's largest storage buffer "
        "({} MB)",
        words.size_bytes() >> 20, max_bytes >> 20));
  const size_t n = words.size(), held = m.shadow.size();
  if (!m.pool.get() || n < held) {  // new, or compacted: everything moved
    gl::upload(m.pool, m.capacity, words.data(), words.size_bytes());
    m.shadow.assign(words.begin(), words.end());
    m.last_words = n;
  } else {
    if (n * 4 > m.capacity) {
      // A stroke over new surface appends blocks: grow by half on the GPU, copying what it
      // holds there, so the bus carries only what the stroke wrote.
      const size_t cap = std::max(n * 4, m.capacity + m.capacity / 2);
      gl::Buffer grown = gl::buffer(nullptr, cap, true);
      glCopyNamedBufferSubData(m.pool.get(), grown.get(), 0, 0, GLsizeiptr(held * 4));
      m.pool = std::move(grown);
      m.capacity = cap;
    }
    // Runs of changed words (gaps under 256 words merged, so a stroke's scattered node
    // rewrites go as a few transfers), plus everything appended after `held`.
    constexpr size_t kGap = 256;
    size_t sent = 0;
    // The shadow follows what is sent, not a copy of the whole pool per update.
    m.shadow.resize(n);
    auto send = [&](size_t lo, size_t hi) {
      glNamedBufferSubData(m.pool.get(), GLintptr(lo * 4), GLsizeiptr((hi - lo) * 4),
                           words.data() + lo);
      std::copy(words.begin() + ptrdiff_t(lo), words.begin() + ptrdiff_t(hi),
                m.shadow.begin() + ptrdiff_t(lo));
      sent += hi - lo;
    };
    // Unchanged stretches are skipped a chunk at a time (memcmp runs at memory speed; a stroke
    // changes a small part of a large pool).
    constexpr size_t kChunk = 1024;
    size_t i = 0, tail = held;
    while (i < held) {
      if (i % kChunk == 0 && i + kChunk <= held &&
          std::memcmp(words.data() + i, m.shadow.data() + i, kChunk * 4) == 0) {
        i += kChunk;
        continue;
      }
      if (words[i] == m.shadow[i]) {
        ++i;
        continue;
      }
      const size_t lo = i;
      size_t hi = i + 1, same = 0;
      for (i = hi; i < held && same < kGap; ++i) {
        if (words[i] != m.shadow[i])
          hi = i + 1, same = 0;
        else
          ++same;
      }
      if (hi == held && n > held) {  // goes out with the appended words
        tail = lo;
        break;
      }
      send(lo, hi);
      i = hi;
    }
    if (n > held) send(tail, n);
    m.last_words = sent;
  }
  gl::check("GpuOctreeTexture::update");
}

size_t GpuOctreeTexture::last_upload_words() const {
  return impl_->last_words;
}

void GpuOctreeTexture::bind(unsigned program, int mode) const {
  bind(program, mode, "oct_", 5);
}

void GpuOctreeTexture::bind(unsigned program, int mode, const std::string& prefix,
                            unsigned binding) const {
  const Impl& m = *impl_;
  const GLuint prog = program;
  auto at = [&](const char* name) { return glGetUniformLocation(prog, (prefix + name).c_str()); };
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, m.pool.get());
  glUniform3d(at("origin"), m.origin[0], m.origin[1], m.origin[2]);
  glUniform1d(at("scale"), m.scale);
  glUniform1f(at("size"), m.size);
  glUniform1ui(at("background"), m.background);
  glUniform1i(at("mode"), mode);
  glUniform3fv(at("tags"), 15, m.tags);
}

GpuOctreeTexture::Lookups GpuOctreeTexture::lookup(std::span<const float> p,
                                                   std::span<const float> n,
                                                   float footprint) const {
  const Impl& m = *impl_;
  const size_t count = p.size() / 3;
  if (!n.empty() && n.size() != p.size())
    throw std::invalid_argument("GpuOctreeTexture::lookup: one normal per point");
  Lookups out;
  out.nearest.resize(count);
  out.nearest_found.resize(count);
  out.filtered.resize(4 * count);
  out.filtered_found.resize(count);
  if (count == 0) return out;
  if (!m.lookup.get()) {
    const std::string cs = std::string("#version 450 core\n#define OCT_LOOKUP_ONLY\n") +
                           shaders::octree + shaders::octree_lookup_comp;
    m.lookup = gl::program("octree lookup", {{GL_COMPUTE_SHADER, cs}});
  }
  const float zero[3] = {0, 0, 0};
  gl::Buffer pts = gl::buffer(p.data(), p.size_bytes());
  gl::Buffer nrm = n.empty() ? gl::buffer(zero, sizeof zero) : gl::buffer(n.data(), n.size_bytes());
  std::vector<uint32_t> res(6 * count);
  gl::Buffer res_buf = gl::buffer(res.data(), res.size() * 4, true);
  const GLuint prog = m.lookup.get();
  glUseProgram(prog);
  bind(prog, 2);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, pts.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 7, nrm.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, res_buf.get());
  glUniform1ui(glGetUniformLocation(prog, "count"), GLuint(count));
  glUniform1i(glGetUniformLocation(prog, "has_normals"), !n.empty());
  glUniform1f(glGetUniformLocation(prog, "footprint"), footprint);
  GLuint query = 0;
  glCreateQueries(GL_TIME_ELAPSED, 1, &query);
  const gl::Query timer(query);
  glBeginQuery(GL_TIME_ELAPSED, query);
  glDispatchCompute(GLuint((count + 63) / 64), 1, 1);
  glEndQuery(GL_TIME_ELAPSED);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glGetNamedBufferSubData(res_buf.get(), 0, GLsizeiptr(res.size() * 4), res.data());
  GLuint64 ns = 0;
  glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
  out.shader_ms = double(ns) * 1e-6;
  glUseProgram(0);
  gl::check("GpuOctreeTexture::lookup");
  for (size_t i = 0; i < count; ++i) {
    out.nearest[i] = res[6 * i];
    out.nearest_found[i] = res[6 * i + 1] & 1;
    out.filtered_found[i] = res[6 * i + 1] >> 1 & 1;
    for (int k = 0; k < 4; ++k) std::memcpy(&out.filtered[4 * i + k], &res[6 * i + 2 + k], 4);
  }
  return out;
}

}  // namespace limn
