#version 450 core
layout(location = 0) in vec3 pos;
layout(location = 1) in vec3 nrm;
layout(location = 2) in vec3 col;
layout(location = 3) in vec3 bary;
layout(location = 4) in vec3 uv;
uniform mat4 view_proj;
out vec3 t_pos;
out vec3 t_nrm;
out vec3 t_col;
out vec3 t_bary;
out vec3 t_uv;
void main() {
  t_pos = pos;
  t_nrm = nrm;
  t_col = col;
  t_bary = bary;
  t_uv = uv;
  gl_Position = view_proj * vec4(pos, 1.0);
}
