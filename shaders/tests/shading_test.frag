/* Compile check of the shading include the way a host material shader uses it: cmake/glow_embed.cmake
 * writes "#version 450 core", band #defines (3/2, 8/8, 1/1) and glow_shading.glsl (includes resolved)
 * before this body, and glslangValidator checks the result at build time. */
layout(binding = 0) uniform sampler3D grid;
layout(binding = 1) uniform usampler3D grid_mask;
layout(binding = 2) uniform sampler2DArray lightmap;
layout(binding = 3) uniform usampler2D lightmap_valid;
layout(binding = 4) uniform sampler2D lightmap_detail;
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 lm_uv;
layout(location = 0) out vec4 color;
void main() {
    vec4 sh[GLOW_SH_PLANES];
    vec3 c = vec3(0.0);
    if (glow_sample_lightmap(lightmap, lightmap_valid, lm_uv, sh))
        c += max(glow_shade_sh(sh, normalize(normal), 1.0) + glow_sample_lightmap_detail(lightmap_detail, lm_uv), 0.0);
    if (glow_sample_grid(grid, grid_mask, vec3(0.0), 0.5, ivec3(8), position, sh)) c += glow_shade_sh(sh, normalize(normal), 20.0);
    color = vec4(c, 1.0);
}
