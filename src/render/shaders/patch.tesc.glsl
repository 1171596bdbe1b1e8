// patch.tesc: tessellation rates per patch edge from the cage lines' rates
layout(vertices = CVS) out;
in vec3 v_pos[];
flat in uint v_patch[];
out vec3 c_pos[];
// The patch travels with every control point: llvmpipe mixes up per-patch outputs ("patch out")
// between patches in large draws, as it does gl_PrimitiveID.
flat out uint c_patch[];
layout(std430, binding = 3) readonly buffer Lines { float line_rate[]; };
uniform int factor;
// Segments of a patch edge of refinement level k on a line of `r` segments at level 0: a power
// of two, so that an edge at level k is exactly twice the two edges at level k + 1 beside it.
float rate(float r, float k) {
  float m = round(log2(max(r, 1.0)));
  return clamp(exp2(m - k), 1.0, 32.0);
}
void main() {
  c_pos[gl_InvocationID] = v_pos[gl_InvocationID];
  c_patch[gl_InvocationID] = v_patch[gl_InvocationID];
  if (gl_InvocationID == 0) {
    uint p = v_patch[0];
    Info I = info[p];
    float k = float(I.bits & 0xFFu);
    uint transition = (I.bits >> 12) & 0xFu;
    float e[4];
    for (int j = 0; j < 4; ++j) {
      bool split = ((transition >> uint(j)) & 1u) != 0u;
      // An edge bordering finer patches takes the sum of their two rates.
      float f = factor > 0 ? float(factor) : rate(line_rate[I.keys[j]], split ? k + 1.0 : k);
      e[j] = split ? 2.0 * f : f;
    }
    // Patch edge j: 0 is v = 0, 1 is u = 1, 2 is v = 1, 3 is u = 0; GL's outer levels run
    // u = 0, v = 0, u = 1, v = 1.
    gl_TessLevelOuter[0] = e[3];
    gl_TessLevelOuter[1] = e[0];
    gl_TessLevelOuter[2] = e[1];
    gl_TessLevelOuter[3] = e[2];
    gl_TessLevelInner[0] = max(e[0], e[2]);
    gl_TessLevelInner[1] = max(e[1], e[3]);
  }
}
