// mesh.frag: MeshDrawer's fragment shader (after shade.glsl, octree.glsl and, with MATERIAL,
// material.glsl)
in vec3 t_pos;
in vec3 t_nrm;
in vec3 t_col;
in vec3 t_bary;
in vec3 t_uv;
uniform vec3 eye;
uniform float uv_checker;
out vec4 frag;
void main() {
  float edge = 1e9;
  if (outline) {
    vec3 d = t_bary / max(fwidth(t_bary), vec3(1e-9));
    edge = min(d.x, min(d.y, d.z));
  }
  vec3 base = t_col;
  if (uv_checker > 0.0 && t_uv.z > 0.5) base = uv_checker_color(t_uv.xy, uv_checker);
#ifdef MATERIAL
  frag = vec4(shade_material(oct_paint(base, t_pos, t_nrm), t_pos, t_nrm, eye, edge, outline), 1.0);
#else
  frag = vec4(shade(oct_paint(base, t_pos, t_nrm), t_pos, t_nrm, eye, edge, outline), 1.0);
#endif
}
