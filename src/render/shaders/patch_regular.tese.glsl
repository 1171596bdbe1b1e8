// patch_regular.tese: regular B-spline patches, as src/subdiv/patch_eval.cpp (the basis is in
// patch_eval.glsl)
void main() {
  float s = gl_TessCoord.x, t = gl_TessCoord.y;
  Info I = info[c_patch[0]];
  vec4 wu, du, wv, dv;
  regular_weights(s, t, I.bits, I.sharpness, wu, du, wv, dv);
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
