// octree_lookup.comp: GpuOctreeTexture::lookup's compute shader (after octree.glsl)
layout(local_size_x = 64) in;
layout(std430, binding = 6) readonly buffer Points { float pts[]; };
layout(std430, binding = 7) readonly buffer Normals { float nrms[]; };
layout(std430, binding = 8) writeonly buffer Out { uint res[]; };
uniform uint count;
uniform bool has_normals;
uniform float footprint;
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  vec3 p = vec3(pts[3u * i], pts[3u * i + 1u], pts[3u * i + 2u]);
  vec3 n = has_normals ? vec3(nrms[3u * i], nrms[3u * i + 1u], nrms[3u * i + 2u]) : vec3(0.0);
  uint col;
  int lv;
  bool nf = oct_nearest(p, n, col, lv);
  vec4 f;
  bool ff = oct_filtered(p, n, footprint, f);
  res[6u * i] = col;
  res[6u * i + 1u] = (nf ? 1u : 0u) | (ff ? 2u : 0u);
  res[6u * i + 2u] = floatBitsToUint(f.r);
  res[6u * i + 3u] = floatBitsToUint(f.g);
  res[6u * i + 4u] = floatBitsToUint(f.b);
  res[6u * i + 5u] = floatBitsToUint(f.a);
}
