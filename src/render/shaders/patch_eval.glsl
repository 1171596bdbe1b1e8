// patch_eval: what both tessellation evaluation shaders share
layout(quads, equal_spacing, ccw) in;
in vec3 c_pos[];
flat in uint c_patch[];
uniform mat4 view_proj;
out vec3 t_pos;
out vec3 t_nrm;
out vec2 t_uv;
flat out uint t_patch;
#ifdef UVS
// UVs of linear channels: each ptex face's four corner values (subdiv's ptex_corner_values).
layout(std430, binding = 4) readonly buffer PtexUvs { vec2 ptex_uvs[]; };
out vec2 t_tex;
#endif
void emit_point(vec3 p, vec3 pu, vec3 pv) {
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
