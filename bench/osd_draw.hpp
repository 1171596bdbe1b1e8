// OpenSubdiv's own GPU drawing for the frame-time benchmark: Far's adaptive patch table
// (isolation level L, Gregory-basis end caps, as limn's fixed depth L) uploaded with
// Osd::GLPatchTable, its refined and local points in an Osd::GLVertexBuffer, drawn by a small
// program around Osd::GLSLPatchShaderSource's common and per-patch-type stages with OpenSubdiv's
// screen-space tessellation (OSD_ENABLE_SCREENSPACE_TESSELLATION) and patch culling
// (OSD_ENABLE_PATCH_CULL), its level set so that a patch edge gets about one segment per
// `pixels_per_segment` pixels like limn's rates.
//
// libosdGPU loads GL through its own loader (dlopen libGL.so.1, glXGetProcAddressARB), whose
// entry points are libglvnd's dispatch stubs: they reach whatever context is current, EGL
// included, so it shares limn's surfaceless context. This file's own GL calls go through libepoxy
// (included first, so OpenSubdiv's <GL/gl.h> is not seen again).
//
// llvmpipe: OpenSubdiv's shaders read each patch's PatchParam by gl_PrimitiveID (plus a base)
// and hand the tessellation levels on in "patch out" variables, both of which llvmpipe 22.3 mixes
// up in large draws. Each patch array is therefore drawn in chunks (the same 32 patches limn's
// drawer uses there), each chunk with its own primitive-id base, and the bench checks the image
// against limn's (coverage agreement).
#pragma once

#include <epoxy/gl.h>

#include <array>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "osd_bench.hpp"
#include "render/gl_util.hpp"  // view and projection of a limn Camera, gl::check

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#include <opensubdiv/osd/glPatchTable.h>
#include <opensubdiv/osd/glVertexBuffer.h>
#include <opensubdiv/osd/glslPatchShaderSource.h>
#pragma GCC diagnostic pop

namespace limn::bench {

class OsdGlDrawer {
 public:
  struct Stats {
    size_t patches = 0, regular = 0, gregory = 0;
    uint64_t triangles = 0;
    double gpu_ms = 0;  ///< the draw's GPU time (a timer query)
  };

  /// Far's adaptive table of `cage` at isolation `level` (single-crease patches only where the
  /// cage has creases, infinitely sharp patches as limn's defaults), uploaded. Throws
  /// std::runtime_error for patch types this drawer has no program for.
  OsdGlDrawer(const Mesh& cage, int level) {
    namespace Far = osd::Far;
    single_crease_ = !cage.crease_sharpness.empty();
    const OsdAdaptive far = osd_adaptive(cage, level, single_crease_, true);
    // Refined points level by level, then the end caps' local points.
    struct P3 {
      float x, y, z;
      void Clear() { x = y = z = 0; }
      void AddWithWeight(const P3& o, float w) { x += w * o.x, y += w * o.y, z += w * o.z; }
    };
    std::vector<P3> verts;
    osd_points(far, cage, verts);
    for (const P3& p : verts)
      for (int k = 0; k < 3; ++k) {
        const float c = k == 0 ? p.x : k == 1 ? p.y : p.z;
        bounds_.min[k] = std::min(bounds_.min[k], c), bounds_.max[k] = std::max(bounds_.max[k], c);
      }

    vertices_.reset(osd::Osd::GLVertexBuffer::Create(3, int(verts.size())));
    vertices_->UpdateData(&verts[0].x, 0, int(verts.size()));
    table_.reset(osd::Osd::GLPatchTable::Create(far.table.get()));
    if (!vertices_ || !table_) throw std::runtime_error("OpenSubdiv: GL buffers not created");

    glCreateVertexArrays(1, &vao_);
    glBindVertexArray(vao_);
    glBindBuffer(GL_ARRAY_BUFFER, vertices_->BindVBO());
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, table_->GetPatchIndexBuffer());
    glBindVertexArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);

    for (const osd::Osd::PatchArray& a : table_->GetPatchArrays()) {
      const auto type = a.GetDescriptor().GetType();
      if (type == Far::PatchDescriptor::REGULAR)
        stats_.regular += size_t(a.GetNumPatches());
      else if (type == Far::PatchDescriptor::GREGORY_BASIS)
        stats_.gregory += size_t(a.GetNumPatches());
      else
        throw std::runtime_error("OpenSubdiv: no program for patch type " + std::to_string(type));
      if (!programs_[slot(type)].get()) programs_[slot(type)] = build(type);
    }
    stats_.patches = stats_.regular + stats_.gregory;
    glCreateQueries(GL_PRIMITIVES_GENERATED, 1, &query_);
    glCreateQueries(GL_TIME_ELAPSED, 1, &timer_);
  }
  ~OsdGlDrawer() {
    glDeleteVertexArrays(1, &vao_);
    glDeleteQueries(1, &query_);
    glDeleteQueries(1, &timer_);
  }
  OsdGlDrawer(const OsdGlDrawer&) = delete;
  OsdGlDrawer& operator=(const OsdGlDrawer&) = delete;

  /// Draws into the bound framebuffer seen by `cam` (depth test on); `chunk`: patches per draw
  /// call (SIZE_MAX: one per patch array). Returns the counts and the triangles rasterised.
  Stats draw(const Camera& cam, float pixels_per_segment, size_t chunk) {
    std::array<float, 16> view, proj;
    gl::view_and_projection(cam, bounds_, view, proj);
    // OsdComputeTessLevel: level = OsdTessLevel() * the projected diameter in NDC units (2 per
    // image height), so this many per NDC unit gives one segment per pixels_per_segment pixels.
    const float tess = float(cam.height) / (2.0f * pixels_per_segment);
    glEnable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glBindVertexArray(vao_);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_BUFFER, table_->GetPatchParamTextureBuffer());
    glBeginQuery(GL_TIME_ELAPSED, timer_);
    glBeginQuery(GL_PRIMITIVES_GENERATED, query_);
    for (const osd::Osd::PatchArray& a : table_->GetPatchArrays()) {
      const GLuint prog = programs_[slot(a.GetDescriptor().GetType())].get();
      const int cvs = a.GetDescriptor().GetNumControlVertices();
      glUseProgram(prog);
      glUniformMatrix4fv(glGetUniformLocation(prog, "u_view"), 1, GL_FALSE, view.data());
      glUniformMatrix4fv(glGetUniformLocation(prog, "u_proj"), 1, GL_FALSE, proj.data());
      glUniform1f(glGetUniformLocation(prog, "u_tess_level"), tess);
      glUniform3fv(glGetUniformLocation(prog, "u_eye"), 1, cam.eye);
      glUniform1i(glGetUniformLocation(prog, "OsdPatchParamBuffer"), 0);
      const GLint base = glGetUniformLocation(prog, "u_primitive_base");
      glPatchParameteri(GL_PATCH_VERTICES, cvs);
      const size_t n = size_t(a.GetNumPatches());
      for (size_t first = 0; first < n; first += chunk) {
        const size_t count = std::min(chunk, n - first);
        glUniform1i(base, a.GetPrimitiveIdBase() + int(first));
        const size_t index = size_t(a.GetIndexBase()) + first * size_t(cvs);
        glDrawElements(GL_PATCHES, GLsizei(count * size_t(cvs)), GL_UNSIGNED_INT,
                       reinterpret_cast<const void*>(index * sizeof(GLuint)));
      }
    }
    glEndQuery(GL_PRIMITIVES_GENERATED);
    glEndQuery(GL_TIME_ELAPSED);
    GLuint64 prims = 0, ns = 0;
    glGetQueryObjectui64v(query_, GL_QUERY_RESULT, &prims);
    glGetQueryObjectui64v(timer_, GL_QUERY_RESULT, &ns);
    glBindVertexArray(0);
    glUseProgram(0);
    gl::check("OsdGlDrawer::draw");
    Stats s = stats_;
    s.triangles = prims;
    s.gpu_ms = double(ns) * 1e-6;
    return s;
  }

  const Stats& stats() const { return stats_; }

 private:
  static int slot(int type) { return type == osd::Far::PatchDescriptor::REGULAR ? 0 : 1; }

  // What OpenSubdiv's shaders leave to the client: matrices, the tessellation level, the
  // primitive-id base of the draw; defined after its common source, which declares them.
  static constexpr const char* kClient = R"(
uniform mat4 u_view, u_proj;
uniform float u_tess_level;
uniform int u_primitive_base;
mat4 OsdModelViewMatrix() { return u_view; }
mat4 OsdProjectionMatrix() { return u_proj; }
mat4 OsdModelViewProjectionMatrix() { return u_proj * u_view; }
float OsdTessLevel() { return u_tess_level; }
int OsdGregoryQuadOffsetBase() { return 0; }
int OsdPrimitiveIdBase() { return u_primitive_base; }
int OsdBaseVertex() { return 0; }
)";

  // Two-sided Blinn-Phong under a head light, as limn's patch fragment shader (view space here).
  static constexpr const char* kFragment = R"(
in block {
  OutputVertex v;
} inpt;
out vec4 frag;
void main() {
  vec3 v = normalize(-inpt.v.position.xyz);
  vec3 n = normalize(inpt.v.normal);
  if (dot(n, v) < 0.0) n = -n;
  float diff = max(dot(n, v), 0.0);
  vec3 h = normalize(v + vec3(0.3, 0.5, 0.0));
  float spec = pow(max(dot(n, h), 0.0), 40.0);
  frag = vec4(vec3(0.78, 0.78, 0.80) * (0.18 + 0.82 * diff) + vec3(0.18 * spec), 1.0);
}
)";

  gl::Program build(osd::Far::PatchDescriptor::Type type) const {
    using Src = osd::Osd::GLSLPatchShaderSource;
    // With OpenSubdiv's frustum culling of patches (levels 0 for a patch whose control points
    // are all beyond one clip plane), as limn coarsens the patches of faces out of view.
    std::string head =
        "#version 450 core\n#define OSD_ENABLE_SCREENSPACE_TESSELLATION\n"
        "#define OSD_ENABLE_PATCH_CULL\n";
    if (single_crease_) head += "#define OSD_PATCH_ENABLE_SINGLE_CREASE\n";
    head += Src::GetCommonShaderSource();
    head += kClient;
    const std::string vs = head + Src::GetVertexShaderSource(type),
                      tc = head + Src::GetTessControlShaderSource(type),
                      te = head + Src::GetTessEvalShaderSource(type), fs = head + kFragment;
    return gl::program("OpenSubdiv patches", {{GL_VERTEX_SHADER, vs},
                                              {GL_TESS_CONTROL_SHADER, tc},
                                              {GL_TESS_EVALUATION_SHADER, te},
                                              {GL_FRAGMENT_SHADER, fs}});
  }

  bool single_crease_ = false;
  Box bounds_;
  std::unique_ptr<osd::Osd::GLVertexBuffer> vertices_;
  std::unique_ptr<osd::Osd::GLPatchTable> table_;
  gl::Program programs_[2];
  GLuint vao_ = 0, query_ = 0, timer_ = 0;
  Stats stats_;
};

}  // namespace limn::bench
