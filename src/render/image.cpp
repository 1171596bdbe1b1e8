#include "limn/render/image.hpp"

#include <fmt/format.h>
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "gl_util.hpp"
#include "limn/mesh/file.hpp"

namespace limn {

struct RenderTarget::Impl {
  gl::Framebuffer fbo, resolve;
  gl::Renderbuffer color, depth, resolve_color;
  int samples = 1;
};

RenderTarget::RenderTarget(int width, int height, int samples)
    : impl_(std::make_unique<Impl>()), width_(width), height_(height) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw std::invalid_argument(
        fmt::format("render target {}x{}: 1-16384 pixels each way", width, height));
  GLint max_samples = 1;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  Impl& m = *impl_;
  m.samples = std::clamp(samples, 1, std::max(1, int(max_samples)));
  auto storage = [&](gl::Renderbuffer& rb, GLenum format, int s) {
    GLuint n = 0;
    glCreateRenderbuffers(1, &n);
    rb = gl::Renderbuffer(n);
    if (s > 1)
      glNamedRenderbufferStorageMultisample(n, s, format, width, height);
    else
      glNamedRenderbufferStorage(n, format, width, height);
  };
  GLuint f = 0;
  glCreateFramebuffers(1, &f);
  m.fbo = gl::Framebuffer(f);
  storage(m.color, GL_RGBA8, m.samples);
  storage(m.depth, GL_DEPTH_COMPONENT32F, m.samples);
  glNamedFramebufferRenderbuffer(f, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, m.color.get());
  glNamedFramebufferRenderbuffer(f, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, m.depth.get());
  if (glCheckNamedFramebufferStatus(f, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error(fmt::format("OpenGL: {}x{} framebuffer incomplete", width, height));
  if (m.samples > 1) {
    glCreateFramebuffers(1, &f);
    m.resolve = gl::Framebuffer(f);
    storage(m.resolve_color, GL_RGBA8, 1);
    glNamedFramebufferRenderbuffer(f, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, m.resolve_color.get());
  }
  gl::check("RenderTarget");
}

RenderTarget::~RenderTarget() = default;

void RenderTarget::begin(const float clear_rgba[4]) {
  glBindFramebuffer(GL_FRAMEBUFFER, impl_->fbo.get());
  glViewport(0, 0, width_, height_);
  glClearNamedFramebufferfv(impl_->fbo.get(), GL_COLOR, 0, clear_rgba);
  const float one = 1.0f;
  glClearNamedFramebufferfv(impl_->fbo.get(), GL_DEPTH, 0, &one);
}

void RenderTarget::finish() {
  glFinish();
}

std::vector<uint8_t> RenderTarget::read_rgba() {
  Impl& m = *impl_;
  GLuint src = m.fbo.get();
  if (m.samples > 1) {
    glBlitNamedFramebuffer(m.fbo.get(), m.resolve.get(), 0, 0, width_, height_, 0, 0, width_,
                           height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    src = m.resolve.get();
  }
  std::vector<uint8_t> px(size_t(width_) * size_t(height_) * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, src);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
  gl::check("RenderTarget::read_rgba");
  // GL's rows run bottom to top.
  const size_t row = size_t(width_) * 4;
  for (size_t y = 0; y < size_t(height_) / 2; ++y)
    std::swap_ranges(px.begin() + long(y * row), px.begin() + long((y + 1) * row),
                     px.begin() + long((size_t(height_) - 1 - y) * row));
  return px;
}

void write_png(const std::filesystem::path& path, int width, int height,
               std::span<const uint8_t> rgba) {
  if (width < 1 || height < 1 || rgba.size() != size_t(width) * size_t(height) * 4)
    throw std::invalid_argument(fmt::format("{}: {} bytes for a {}x{} RGBA image", path.string(),
                                            rgba.size(), width, height));
  std::string bytes;
  auto sink = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
  };
  if (!stbi_write_png_to_func(sink, &bytes, width, height, 4, rgba.data(), width * 4))
    throw std::runtime_error(fmt::format("{}: PNG encoding failed", path.string()));
  write_file_atomic(path, bytes);
}

std::vector<uint8_t> read_png(const std::filesystem::path& path, int& width, int& height) {
  int n = 0;
  stbi_uc* data = stbi_load(path.string().c_str(), &width, &height, &n, 4);
  if (!data)
    throw InputError(
        fmt::format("{}: not a readable image ({})", path.string(), stbi_failure_reason()));
  std::vector<uint8_t> px(data, data + size_t(width) * size_t(height) * 4);
  stbi_image_free(data);
  return px;
}

}  // namespace limn
