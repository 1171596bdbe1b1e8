// patch.frag: PatchDrawer's fragment shader (after shade.glsl, octree.glsl and, with MATERIAL,
// material.glsl)
in vec3 t_pos;
in vec3 t_nrm;
in vec2 t_uv;
flat in uint t_patch;
#ifdef UVS
in vec2 t_tex;
uniform float uv_checker;
#endif
uniform vec3 eye;
uniform vec3 base;
uniform vec3 ramp[17];
out vec4 frag;
// Options are compiled in, not uniforms: llvmpipe runs both sides of a branch on a uniform.
#ifdef DEPTH_COLORS
const bool depth_colors = true;
#else
const bool depth_colors = false;
#endif
void main() {
  vec3 c = base;
  if (depth_colors) c = ramp[min(info[t_patch].bits & 0xFFu, 16u)];
#ifdef UVS
  c = uv_checker_color(t_tex, uv_checker);
#endif
  c = oct_paint(c, t_pos, t_nrm);
  float edge = 1e9;
  if (outline) {
    vec2 d = min(t_uv, 1.0 - t_uv) / max(fwidth(t_uv), vec2(1e-9));
    edge = min(d.x, d.y);
  }
#ifdef MATERIAL
  frag = vec4(shade_material(c, t_pos, t_nrm, eye, edge, outline), 1.0);
#else
  frag = vec4(shade(c, t_pos, t_nrm, eye, edge, outline), 1.0);
#endif
}
