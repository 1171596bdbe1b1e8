// patch_eval: what both tessellation evaluation shaders share
layout(quads, equal_spacing, ccw) in;
in vec3 c_pos[];
flat in uint c_patch[];
uniform mat4 view_proj;
out vec3 t_pos;
out vec3 t_nrm;
out vec2 t_uv;
flat out uint t_patch;
void bspline(float t, out vec4 w, out vec4 d) {
  float s = 1.0 - t, t2 = t * t, t3 = t2 * t;
  w = vec4(s * s * s, 3.0 * t3 - 6.0 * t2 + 4.0, -3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0, t3) / 6.0;
  d = vec4(-0.5 * s * s, 1.5 * t2 - 2.0 * t, -1.5 * t2 + t + 0.5, 0.5 * t2);
}
// An extrapolated end point (2 next - next but one) folded into the other weights.
vec4 fold(vec4 w, bool lo, bool hi) {
  if (lo) { w.y += 2.0 * w.x; w.z -= w.x; w.x = 0.0; }
  if (hi) { w.z += 2.0 * w.w; w.y -= w.w; w.w = 0.0; }
  return w;
}
// The limit basis of a cubic curve whose point 1 is a semi-sharp vertex of sharpness s.
void crease_basis(float t, float s, out vec4 w, out vec4 d) {
  mat4 A = mat4(1.0);  // rows: the current segment's points over the original four
  float scale = 1.0;
  for (int guard = 0; guard < 16 && s > 0.0; ++guard) {
    float a = min(s, 1.0);
    vec4 v1 = vec4((1.0 - a) / 8.0, a + (1.0 - a) * 0.75, (1.0 - a) / 8.0, 0.0);
    vec4 e01 = vec4(0.5, 0.5, 0.0, 0.0), e12 = vec4(0.0, 0.5, 0.5, 0.0);
    vec4 e23 = vec4(0.0, 0.0, 0.5, 0.5), v2 = vec4(0.0, 0.125, 0.75, 0.125);
    mat4 M;  // GLSL matrices are column-major: build with rows transposed
    if (t < 0.5) {
      M = transpose(mat4(e01, v1, e12, v2));
      t *= 2.0; scale *= 2.0; s -= 1.0;
    } else {
      M = transpose(mat4(v1, e12, v2, e23));
      t = 2.0 * t - 1.0; scale *= 2.0; s = 0.0;
    }
    A = M * A;
  }
  vec4 b, db;
  bspline(t, b, db);
  w = b * A;            // w_j = sum_i b_i A[i][j]
  d = (db * A) * scale;
}
void bezier(float t, out vec4 w, out vec4 d) {
  float s = 1.0 - t;
  w = vec4(s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t);
  d = vec4(-3.0 * s * s, 3.0 * s * s - 6.0 * t * s, 6.0 * t * s - 3.0 * t * t, 3.0 * t * t);
}
// The B-spline weights and derivatives of a regular patch at (s, t): boundary edges
// extrapolated, a single crease along its edge (bits as Info's).
void regular_weights(float s, float t, uint bits, float sharpness, out vec4 wu, out vec4 du,
                     out vec4 wv, out vec4 dv) {
  uint boundary = (bits >> 8) & 0xFu;
  bspline(s, wu, du);
  bspline(t, wv, dv);
  wu = fold(wu, (boundary & 8u) != 0u, (boundary & 2u) != 0u);
  du = fold(du, (boundary & 8u) != 0u, (boundary & 2u) != 0u);
  wv = fold(wv, (boundary & 1u) != 0u, (boundary & 4u) != 0u);
  dv = fold(dv, (boundary & 1u) != 0u, (boundary & 4u) != 0u);
  if (((bits >> 16) & 3u) == 2u) {  // single crease along edge ce, at the basis' t = 0
    uint ce = (bits >> 18) & 3u;
    float x = ce == 0u ? t : ce == 2u ? 1.0 - t : ce == 3u ? s : 1.0 - s;
    vec4 cw, cd;
    crease_basis(x, sharpness, cw, cd);
    if (ce == 1u || ce == 2u) { cw = cw.wzyx; cd = -cd.wzyx; }
    if (ce == 0u || ce == 2u) { wv = cw; dv = cd; } else { wu = cw; du = cd; }
  }
}
#ifdef SMOOTH_UVS
// UVs of smooth channels: per patch, its face-varying patch (subdiv's FaceVaryingPatches) at the
// same place: 16 B-spline or 20 Gregory control values, bits as Info's (type 1: an end cap).
struct UvPatch { vec2 cv[20]; uint bits; float sharpness; };
layout(std430, binding = 5) readonly buffer UvPatches { UvPatch uv_patch[]; };
out vec2 t_tex;
vec2 smooth_uv(uint p, float s, float t) {
  uint bits = uv_patch[p].bits;
  vec2 r = vec2(0.0);
  if (((bits >> 16) & 3u) != 1u) {
    vec4 wu, du, wv, dv;
    regular_weights(s, t, bits, uv_patch[p].sharpness, wu, du, wv, dv);
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 4; ++x) r += wv[y] * wu[x] * uv_patch[p].cv[4 * y + x];
    return r;
  }
  // Gregory: the 12 boundary points, then each corner's interior point blended from Fp and Fm.
  const ivec3 slot[12] = ivec3[12](ivec3(0, 0, 0), ivec3(1, 0, 1), ivec3(2, 0, 7), ivec3(3, 0, 5),
                                   ivec3(0, 1, 2), ivec3(3, 1, 6), ivec3(0, 2, 16), ivec3(3, 2, 12),
                                   ivec3(0, 3, 15), ivec3(1, 3, 17), ivec3(2, 3, 11),
                                   ivec3(3, 3, 10));
  vec4 wu, du, wv, dv;
  bezier(s, wu, du);
  bezier(t, wv, dv);
  for (int i = 0; i < 12; ++i) r += wu[slot[i].x] * wv[slot[i].y] * uv_patch[p].cv[slot[i].z];
  float a[4] = float[4](s, t, 1.0 - s, 1.0 - t);
  float D[4] = float[4](s + t, t + 1.0 - s, 2.0 - s - t, 1.0 - t + s);
  const ivec3 inner[4] = ivec3[4](ivec3(1, 1, 3), ivec3(2, 1, 8), ivec3(2, 2, 13), ivec3(1, 2, 18));
  for (int i = 0; i < 4; ++i) {
    float g = D[i] > 0.0 ? a[i] / D[i] : 0.5;
    ivec3 b = inner[i];
    r += wu[b.x] * wv[b.y] * (g * uv_patch[p].cv[b.z] + (1.0 - g) * uv_patch[p].cv[b.z + 1]);
  }
  return r;
}
#endif
#ifdef UVS
// UVs of linear channels: each ptex face's four corner values (subdiv's ptex_corner_values).
layout(std430, binding = 4) readonly buffer PtexUvs { vec2 ptex_uvs[]; };
out vec2 t_tex;
#endif
void emit_point(vec3 p, vec3 pu, vec3 pv) {
#ifdef SMOOTH_UVS
  t_tex = smooth_uv(c_patch[0], gl_TessCoord.x, gl_TessCoord.y);
#endif
#ifdef UVS
  Info I = info[c_patch[0]];
  float scale = 1.0 / float(1u << ((I.bits >> 20) & 31u));
  vec2 q = (vec2(float(I.ptex_uv & 0xFFFFu), float(I.ptex_uv >> 16)) + gl_TessCoord.xy) * scale;
  uint b = 4u * I.ptex;
  t_tex = mix(mix(ptex_uvs[b], ptex_uvs[b + 1u], q.x), mix(ptex_uvs[b + 3u], ptex_uvs[b + 2u], q.x),
              q.y);
#endif
  vec3 n = cross(pu, pv);
  if (dot(n, n) < 1e-30) n = cross(c_pos[CVS - 1] - c_pos[0], c_pos[CVS / 2] - c_pos[CVS / 4]);
  t_pos = p;
  t_nrm = n;
  t_uv = gl_TessCoord.xy;
  t_patch = c_patch[0];
  gl_Position = view_proj * vec4(p, 1.0);
}
