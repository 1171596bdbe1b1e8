// patch_eval: what both tessellation evaluation shaders share
layout(quads, equal_spacing, ccw) in;
in vec3 c_pos[];
flat in uint c_patch[];
uniform mat4 view_proj;
out vec3 t_pos;
out vec3 t_nrm;
out vec2 t_uv;
flat out uint t_patch;
void emit_point(vec3 p, vec3 pu, vec3 pv) {
  vec3 n = cross(pu, pv);
  if (dot(n, n) < 1e-30) n = cross(c_pos[CVS - 1] - c_pos[0], c_pos[CVS / 2] - c_pos[CVS / 4]);
  t_pos = p;
  t_nrm = n;
  t_uv = gl_TessCoord.xy;
  t_patch = c_patch[0];
  gl_Position = view_proj * vec4(p, 1.0);
}
