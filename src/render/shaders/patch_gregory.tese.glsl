// patch_gregory.tese: Gregory end caps, as src/subdiv/patch_eval.cpp (bezier() is in
// patch_eval.glsl)
const ivec3 kSlot[12] = ivec3[12](ivec3(0, 0, 0), ivec3(1, 0, 1), ivec3(2, 0, 7), ivec3(3, 0, 5),
                                   ivec3(0, 1, 2), ivec3(3, 1, 6), ivec3(0, 2, 16), ivec3(3, 2, 12),
                                   ivec3(0, 3, 15), ivec3(1, 3, 17), ivec3(2, 3, 11),
                                   ivec3(3, 3, 10));
void main() {
  float s = gl_TessCoord.x, t = gl_TessCoord.y;
  vec4 wu, du, wv, dv;
  bezier(s, wu, du);
  bezier(t, wv, dv);
  vec3 p = vec3(0.0), pu = vec3(0.0), pv = vec3(0.0);
  for (int i = 0; i < 12; ++i) {
    ivec3 b = kSlot[i];
    vec3 c = c_pos[b.z];
    p += wu[b.x] * wv[b.y] * c;
    pu += du[b.x] * wv[b.y] * c;
    pv += wu[b.x] * dv[b.y] * c;
  }
  // Interior point of corner i: (a Fp + (D - a) Fm) / D with a and D linear in (s, t).
  float a[4] = float[4](s, t, 1.0 - s, 1.0 - t);
  vec2 ad[4] = vec2[4](vec2(1, 0), vec2(0, 1), vec2(-1, 0), vec2(0, -1));
  float D[4] = float[4](s + t, t + 1.0 - s, 2.0 - s - t, 1.0 - t + s);
  vec2 Dd[4] = vec2[4](vec2(1, 1), vec2(-1, 1), vec2(-1, -1), vec2(1, -1));
  ivec3 slot[4] = ivec3[4](ivec3(1, 1, 3), ivec3(2, 1, 8), ivec3(2, 2, 13), ivec3(1, 2, 18));
  for (int i = 0; i < 4; ++i) {
    float g = 0.5;
    vec2 gd = vec2(0.0);
    if (D[i] > 0.0) {
      g = a[i] / D[i];
      gd = (ad[i] * D[i] - a[i] * Dd[i]) / (D[i] * D[i]);
    }
    ivec3 b = slot[i];
    float w = wu[b.x] * wv[b.y], w_u = du[b.x] * wv[b.y], w_v = wu[b.x] * dv[b.y];
    vec3 fp = c_pos[b.z], fm = c_pos[b.z + 1];
    vec3 f = g * fp + (1.0 - g) * fm, fdiff = fp - fm;
    p += w * f;
    pu += w_u * f + w * gd.x * fdiff;
    pv += w_v * f + w * gd.y * fdiff;
  }
  emit_point(p, pu, pv);
}
