// patch_info: the per-patch records PatchDrawer uploads
// bits: level | boundary << 8 | transition << 12 | type << 16 | crease edge << 18 | depth << 20;
// ptex, ptex_uv: the patch's ptex face and its origin there (u | v << 16, units of 2^-depth).
struct Info { uvec4 keys; uint bits; float sharpness; uint ptex, ptex_uv; };
layout(std430, binding = 2) readonly buffer Infos { Info info[]; };
