// patch_regular.tese: regular B-spline patches, as src/subdiv/patch_eval.cpp
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
void main() {
  float s = gl_TessCoord.x, t = gl_TessCoord.y;
  Info I = info[c_patch[0]];
  uint boundary = (I.bits >> 8) & 0xFu;
  vec4 wu, du, wv, dv;
  bspline(s, wu, du);
  bspline(t, wv, dv);
  wu = fold(wu, (boundary & 8u) != 0u, (boundary & 2u) != 0u);
  du = fold(du, (boundary & 8u) != 0u, (boundary & 2u) != 0u);
  wv = fold(wv, (boundary & 1u) != 0u, (boundary & 4u) != 0u);
  dv = fold(dv, (boundary & 1u) != 0u, (boundary & 4u) != 0u);
  if (((I.bits >> 16) & 3u) == 2u) {  // single crease along edge ce, at the basis' t = 0
    uint ce = (I.bits >> 18) & 3u;
    float x = ce == 0u ? t : ce == 2u ? 1.0 - t : ce == 3u ? s : 1.0 - s;
    vec4 cw, cd;
    crease_basis(x, I.sharpness, cw, cd);
    if (ce == 1u || ce == 2u) { cw = cw.wzyx; cd = -cd.wzyx; }
    if (ce == 0u || ce == 2u) { wv = cw; dv = cd; } else { wu = cw; du = cd; }
  }
  vec3 p = vec3(0.0), pu = vec3(0.0), pv = vec3(0.0);
  for (int y = 0; y < 4; ++y) {
    vec3 rp = vec3(0.0), ru = vec3(0.0);
    for (int x = 0; x < 4; ++x) {
      vec3 c = c_pos[4 * y + x];
      rp += wu[x] * c;
      ru += du[x] * c;
    }
    p += wv[y] * rp;
    pu += wv[y] * ru;
    pv += dv[y] * rp;
  }
  emit_point(p, pu, pv);
}
