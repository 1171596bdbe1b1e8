// material: physically based shading of a painted material (after shade.glsl, octree.glsl and
// its rmh_ copy, which reads the RMH texture: roughness, metallic, height). GGX normal
// distribution (Walter et al. 2007) with Smith-Schlick visibility (k = alpha / 2) and Schlick's
// Fresnel, metalness as glTF's metallic-roughness model has it (F0 = mix(0.04, base, metallic),
// no diffuse from metal); height as a bump: the normal tilted by the surface gradient of the
// height's screen-space derivatives (Mikkelsen, "Bump Mapping Unparametrized Surfaces on the
// GPU", 2010), the same relief a normal map baked from it gives. Lit like shade(): a head light,
// a key light and a little ambient, in linear light (sRGB base colour decoded, result encoded).
uniform float height_scale;

// Roughness, metallic, height at a fragment: the RMH lookup over the channels' defaults.
vec3 rmh_channels(vec3 pos, vec3 nrm, float footprint) {
  vec4 f;
  if (!rmh_filtered(pos, nrm, footprint, f)) f = vec4(0.0);
  vec4 d = rmh_unpack(rmh_background);
  return f.rgb * f.a + d.rgb * (1.0 - f.a);
}

vec3 shade_material(vec3 base, vec3 pos, vec3 nrm, vec3 eye, float edge, bool outline) {
  vec3 v = normalize(eye - pos);
  vec3 n = normalize(nrm);
  if (dot(n, v) < 0.0) n = -n;  // two-sided, as shade()
  vec3 dpdx = dFdx(pos), dpdy = dFdy(pos);
  float footprint = max(length(dpdx), length(dpdy));
  vec3 m = rmh_channels(pos, nrm, footprint);
  // Bump: displacement (height - 0.5) * height_scale along n. Its screen derivatives come from
  // two more lookups a pixel away on the tangent plane: dFdx of the lookup itself showed every
  // triangle edge as a crease on llvmpipe.
  float dhdx = (rmh_channels(pos + dpdx, nrm, footprint).z - m.z) * height_scale;
  float dhdy = (rmh_channels(pos + dpdy, nrm, footprint).z - m.z) * height_scale;
  vec3 r1 = cross(dpdy, n), r2 = cross(n, dpdx);
  float det = dot(dpdx, r1);
  vec3 grad = sign(det) * (dhdx * r1 + dhdy * r2);
  vec3 nb = abs(det) > 0.0 ? normalize(abs(det) * n - grad) : n;

  const float pi = 3.14159265;
  vec3 albedo = pow(clamp(base, 0.0, 1.0), vec3(2.2));
  float rough = clamp(m.x, 0.03, 1.0), metal = clamp(m.y, 0.0, 1.0);
  float a = rough * rough, a2 = a * a, k = 0.5 * a;
  vec3 f0 = mix(vec3(0.04), albedo, metal);
  // Ambient: a dim diffuse term and a grey surrounding mirrored by the specular colour, blurrier
  // with roughness (metal has no diffuse: without it, it would be black off its highlights).
  vec3 c = 0.1 * albedo * (1.0 - metal) + (0.55 - 0.3 * rough) * f0;
  float nv = max(dot(nb, v), 1e-4);
  for (int i = 0; i < 2; ++i) {
    vec3 l = i == 0 ? v : normalize(v + vec3(0.3, 0.5, 0.0));
    float power = i == 0 ? 0.8 : 0.45;
    float nl = dot(nb, l);
    if (nl <= 0.0) continue;
    vec3 hv = normalize(v + l);
    float nh = max(dot(nb, hv), 0.0), vh = max(dot(v, hv), 0.0);
    float dd = nh * nh * (a2 - 1.0) + 1.0;
    float D = a2 / (pi * dd * dd);
    float G = nl / (nl * (1.0 - k) + k) * nv / (nv * (1.0 - k) + k);
    vec3 F = f0 + (1.0 - f0) * pow(clamp(1.0 - vh, 0.0, 1.0), 5.0);  // pow: never of a negative
    vec3 spec = D * G * F / (4.0 * nl * nv);
    vec3 diff = (1.0 - F) * (1.0 - metal) * albedo / pi;
    c += (diff + spec) * nl * power * pi;
  }
  c = pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2));
  if (outline) c = mix(vec3(0.06), c, smoothstep(0.6, 1.6, edge));
  return c;
}
