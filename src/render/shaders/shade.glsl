// shade: the shading shared by the patch and mesh programs: two-sided Blinn-Phong under a head
// light, with an optional outline where `edge` (0 on an edge, growing inwards) is small; the
// program's `outline` flag (#define OUTLINE: compiled in, not a uniform, since llvmpipe runs both
// sides of a branch on a uniform).
#ifdef OUTLINE
const bool outline = true;
#else
const bool outline = false;
#endif
// The --uv-checker colour at UV `uv`: light and dark squares, `n` per UV unit, tinted red along u
// and green along v within each unit square (so flips and seams show).
vec3 uv_checker_color(vec2 uv, float n) {
  vec2 q = floor(uv * n);
  float dark = mod(q.x + q.y, 2.0);
  vec3 tint = vec3(0.35 + 0.65 * fract(uv.x), 0.35 + 0.65 * fract(uv.y), 0.6);
  return tint * (dark > 0.5 ? 0.45 : 1.0);
}
vec3 shade(vec3 base, vec3 pos, vec3 nrm, vec3 eye, float edge, bool outline) {
  vec3 v = normalize(eye - pos);
  vec3 n = normalize(nrm);
  if (dot(n, v) < 0.0) n = -n;  // two-sided: open surfaces and inverted cages look right
  float diff = max(dot(n, v), 0.0);
  vec3 h = normalize(v + vec3(0.3, 0.5, 0.0));
  float spec = pow(max(dot(n, h), 0.0), 40.0);
  vec3 c = base * (0.18 + 0.82 * diff) + vec3(0.18 * spec);
  if (outline) c = mix(vec3(0.06), c, smoothstep(0.6, 1.6, edge));
  return c;
}
