// patch_info: the per-patch records PatchDrawer uploads
struct Info { uvec4 keys; uint bits; float sharpness; uint pad0, pad1; };
layout(std430, binding = 2) readonly buffer Infos { Info info[]; };
