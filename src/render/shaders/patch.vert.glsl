// patch.vert: PatchDrawer's vertex shader (CVS: control points per patch)
layout(std430, binding = 0) readonly buffer Points { float pts[]; };
layout(std430, binding = 1) readonly buffer Cvs { uint cvs[]; };
uniform uint patch_base;
out vec3 v_pos;
flat out uint v_patch;
void main() {
  // The patch comes from the vertex index: gl_PrimitiveID restarts every 1024 patch vertices on
  // llvmpipe.
  uint i = uint(gl_VertexID);
  uint p = cvs[i];
  v_pos = vec3(pts[3u * p], pts[3u * p + 1u], pts[3u * p + 2u]);
  v_patch = patch_base + i / uint(CVS);
}
