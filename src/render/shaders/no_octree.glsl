// no_octree: oct_paint without a texture (returns `base`): what programs drawn without a texture
// compile instead of octree.glsl, since llvmpipe runs both sides of a branch on a uniform with
// lanes masked off, so the whole octree walk (in double precision) would cost every fragment.
vec3 oct_paint(vec3 base, vec3 pos, vec3 nrm) { return base; }
