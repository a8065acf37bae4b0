/*
 * glow_shading.glsl — what a host's material shader #includes to shade with Glow's caches: sample the
 * grid (dynamic objects) or the lightmap (static surfaces) and convolve with a diffuse or Phong lobe
 * (PIC 3.2, App. B). The same maths as the runtime's C reference (glow.h: glow_sample_grid,
 * glow_sample_lightmap, glow_shade_sh); tests/gpu checks them against each other.
 *
 * THE TEXTURES (glow_gl.h, glow_gl_outputs): coefficients of a cache are Y luma², Co chroma², Cg chroma²
 * (incident radiance, W/(m²·sr), YCoCg), 4 per RGBA32F or RGBA16F texel ("planes", GLOW_SH_PLANES of them):
 *   grid      sampler3D, dims (dx, dy, dz · planes): plane p of cell (x,y,z) at texel (x, y, z + p·dz)
 *   grid mask usampler3D RG32UI (dx, dy, dz): for the cell whose lowest corner is (x,y,z) and each octant o
 *             of it, byte o (x: octants 0-3, y: 4-7) has bit k set when corner k may be blended (it holds a
 *             cache and, with the bake's GVIS, is visible from that octant's centre)
 *   lightmap  sampler2DArray, layer p = plane p; lightmap valid: usampler2D R8UI, 1 where a texel holds a cache.
 *             A lightmap of P pages (bake format 1.7, glow_gl_outputs.lightmap_pages): plane p of page g at
 *             layer g · planes + p, and the valid mask P pages high (page g's rows from g · height):
 *             glow_sample_lightmap_page, glow_sample_lightmap_detail_page with the triangle's page
 *   a refined grid's bricks (glow_gl_outputs grid_brick/fine/fine_mask_texture): glow_sample_grid_refined
 * Lookups use texelFetch and weight empty/hidden neighbours 0 (renormalising the rest). glow_gl creates the
 * textures with NEAREST filtering; do not sample the integer mask/valid textures through a sampler object with
 * a LINEAR filter (an integer texture is then incomplete and every fetch returns 0).
 *
 * USAGE (GLSL 4.50, in any stage)
 *   #define GLOW_SH_BANDS_LUMA 3          (the system's bands: glow_gl_outputs.sh_bands_luma / _chroma)
 *   #define GLOW_SH_BANDS_CHROMA 3
 *   #include "glow_shading.glsl"
 *   vec4 sh[GLOW_SH_PLANES];
 *   if (glow_sample_lightmap(lm, lm_valid, uv, sh))
 *       color += albedo * max(glow_shade_sh(sh, n, 1.0) + glow_sample_lightmap_detail(detail, uv), 0.0);
 * glow_shade_sh(sh, n, 1) is the cosine-weighted mean incident radiance E/π, so a Lambertian surface of
 * albedo ρ reflects ρ · glow_shade_sh(...); for a glossy lobe pass the reflection vector and its exponent,
 * or glow_shade_sh_factors with a GGX lobe's zonal factors (docs/glossy.md).
 * The lightmap detail (bakes with one: glow_gl_outputs.lightmap_detail_texture) adds the light of
 * surfaces beside the texel that the lightmap is too coarse for; leave it out for glossy lobes.
 */
#ifndef GLOW_SHADING_GLSL
#define GLOW_SHADING_GLSL

#ifndef GLOW_SH_BANDS_LUMA
#error "define GLOW_SH_BANDS_LUMA (and GLOW_SH_BANDS_CHROMA) to the system's band counts before including glow_shading.glsl"
#endif
#ifndef GLOW_SH_BANDS_CHROMA
#define GLOW_SH_BANDS_CHROMA GLOW_SH_BANDS_LUMA
#endif
#ifndef GLOW_SH_MAX_BANDS
#define GLOW_SH_MAX_BANDS GLOW_SH_BANDS_LUMA
#endif
#include "glow_sh.glsl"

#define GLOW_SH_L2 (GLOW_SH_BANDS_LUMA * GLOW_SH_BANDS_LUMA)
#define GLOW_SH_C2 (GLOW_SH_BANDS_CHROMA * GLOW_SH_BANDS_CHROMA)
#define GLOW_SH_COEFFS (GLOW_SH_L2 + 2 * GLOW_SH_C2)
#define GLOW_SH_PLANES ((GLOW_SH_COEFFS + 3) / 4)

/** Coefficient k of a cache held in planes. */
float glow_sh_coeff(vec4 sh[GLOW_SH_PLANES], int k) { return sh[k >> 2][k & 3]; }

/** glow_shade_sh with any zonal lobe (glow.h glow_shade_sh_factors): s[l] multiplies band l. For a GGX
 * layer pass the reflection vector and the factors of glow_sh_ggx_lobe_factors(roughness) (computed on
 * the host, per material, e.g. as a uniform array), then scale by F0·A + B from
 * glow_ggx_specular_albedo (a 2D table over cos θ_o and roughness); docs/glossy.md. */
vec3 glow_shade_sh_factors(vec4 sh[GLOW_SH_PLANES], vec3 axis, float s[GLOW_SH_BANDS_LUMA]) {
    float y[GLOW_SH_MAX_BANDS * GLOW_SH_MAX_BANDS];
    glow_sh_eval(GLOW_SH_BANDS_LUMA, axis, y);
    vec3 ycc = vec3(0.0);
    for (int l = 0; l < GLOW_SH_BANDS_LUMA; ++l) {
        vec3 acc = vec3(0.0);
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
            acc.x += glow_sh_coeff(sh, k) * y[k];
            if (l < GLOW_SH_BANDS_CHROMA) {
                acc.y += glow_sh_coeff(sh, GLOW_SH_L2 + k) * y[k];
                acc.z += glow_sh_coeff(sh, GLOW_SH_L2 + GLOW_SH_C2 + k) * y[k];
            }
        }
        ycc += s[l] * acc;
    }
    return glow_ycocg_to_rgb(ycc);
}

/** Lobe-weighted mean incident radiance (RGB, W/(m²·sr)) around unit `axis` for the normalised Phong
 * lobe of `exponent` (1 = diffuse: E/π). */
vec3 glow_shade_sh(vec4 sh[GLOW_SH_PLANES], vec3 axis, float exponent) {
    float s[GLOW_SH_BANDS_LUMA];
    for (int l = 0; l < GLOW_SH_BANDS_LUMA; ++l) s[l] = glow_sh_lobe_factor(l, exponent);
    return glow_shade_sh_factors(sh, axis, s);
}

/* glow_sample_grid_oriented's constants: glow.h's GLOW_GRID_NORMAL_BIAS and GLOW_GRID_BACKFACE_FLOOR */
const float GLOW_GRID_NORMAL_BIAS = 0.25;
const float GLOW_GRID_BACKFACE_FLOOR = 0.2;

/* The lookup of glow_sample_grid (oriented = false) and glow_sample_grid_oriented (unit n): the cell
 * of the moved point p (p0 moved along n), backface weights about p0. */
bool glow__grid_lookup(sampler3D grid, usampler3D grid_mask, vec3 origin, float spacing, ivec3 dims, vec3 p, vec3 p0,
                       bool oriented, vec3 n, out vec4 sh[GLOW_SH_PLANES]) {
    for (int q = 0; q < GLOW_SH_PLANES; ++q) sh[q] = vec4(0.0);
    vec3 f = clamp((p - origin) / spacing, vec3(0.0), vec3(dims - 1));
    vec3 fl = floor(f);
    ivec3 i0 = ivec3(fl), i1 = min(i0 + 1, dims - 1);
    vec3 t = f - fl;
    uint oct = (t.x >= 0.5 ? 1u : 0u) | (t.y >= 0.5 ? 2u : 0u) | (t.z >= 0.5 ? 4u : 0u);
    uvec2 m2 = texelFetch(grid_mask, i0, 0).xy;
    uint mask = ((oct < 4u ? m2.x : m2.y) >> (8u * (oct & 3u))) & 0xFFu;
    float wsum = 0.0;
    for (int c = 0; c < 8; ++c) {
        if (((mask >> uint(c)) & 1u) == 0u) continue;
        ivec3 cc = ivec3((c & 1) != 0 ? i1.x : i0.x, (c & 2) != 0 ? i1.y : i0.y, (c & 4) != 0 ? i1.z : i0.z);
        float w = ((c & 1) != 0 ? t.x : 1.0 - t.x) * ((c & 2) != 0 ? t.y : 1.0 - t.y) * ((c & 4) != 0 ? t.z : 1.0 - t.z);
        if (!(w > 0.0)) continue;
        if (oriented) { /* corners behind the surface count less */
            vec3 d = origin + spacing * vec3(cc) - p0;
            float len = length(d);
            float h = len > 0.0 ? 0.5 * (1.0 + dot(d, n) / len) : 1.0;
            w *= h * h + GLOW_GRID_BACKFACE_FLOOR;
        }
        wsum += w;
        for (int q = 0; q < GLOW_SH_PLANES; ++q) sh[q] += w * texelFetch(grid, cc + ivec3(0, 0, q * dims.z), 0);
    }
    if (!(wsum > 0.0)) return false;
    for (int q = 0; q < GLOW_SH_PLANES; ++q) sh[q] /= wsum;
    return true;
}

/** Trilinear lookup of the grid at `p` (m; clamped to the grid), blending only the corners the mask allows,
 * renormalised. origin = centre of cell (0,0,0), spacing in m, dims = cells (dx, dy, dz).
 * \returns false (sh zeroed) when no corner may be blended. */
bool glow_sample_grid(sampler3D grid, usampler3D grid_mask, vec3 origin, float spacing, ivec3 dims, vec3 p,
                      out vec4 sh[GLOW_SH_PLANES]) {
    return glow__grid_lookup(grid, grid_mask, origin, spacing, dims, p, p, false, vec3(0.0), sh);
}

/** The grid's light for a surface point p with normal n (any length > 0), as glow.h's
 * glow_sample_grid_oriented: the lookup moves GLOW_GRID_NORMAL_BIAS spacings along n, and corners behind
 * the surface are weighted down by ((1 + cos)/2)² + GLOW_GRID_BACKFACE_FLOOR. Use it to shade dynamic
 * objects. \returns as glow_sample_grid. */
bool glow_sample_grid_oriented(sampler3D grid, usampler3D grid_mask, vec3 origin, float spacing, ivec3 dims, vec3 p,
                               vec3 n, out vec4 sh[GLOW_SH_PLANES]) {
    vec3 u = normalize(n);
    return glow__grid_lookup(grid, grid_mask, origin, spacing, dims, p + GLOW_GRID_NORMAL_BIAS * spacing * u, p, true, u, sh);
}

/** A refined grid's lookup (glow_gl_outputs: grid_refine R > 1, its brick, fine and fine mask textures, atlas_x
 * bricks a row), as glow.h's glow_sample_grid (oriented = false) or glow_sample_grid_oriented (oriented,
 * normal n): a point inside a brick blends its fine cell's corners, else (or when none of them may be
 * blended) the coarse cell's; the oriented lookup moves a quarter of the fine spacing along n.
 * \returns false (sh zeroed) when no corner may be blended. */
bool glow_sample_grid_refined(sampler3D grid, usampler3D grid_mask, usampler3D bricks, sampler3D fine,
                              usampler3D fine_mask, int refine, int atlas_x, vec3 origin, float spacing, ivec3 dims,
                              vec3 p0, bool oriented, vec3 n, out vec4 sh[GLOW_SH_PLANES]) {
    vec3 u = oriented ? normalize(n) : vec3(0.0);
    float h = spacing / float(refine);
    vec3 p = oriented ? p0 + GLOW_GRID_NORMAL_BIAS * h * u : p0;
    vec3 f = (p - origin) / spacing;
    if (all(greaterThanEqual(f, vec3(0.0))) && all(lessThanEqual(f, vec3(dims - 1)))) {
        ivec3 i0 = ivec3(floor(f));
        ivec3 c0 = ivec3(i0.x + 1 < dims.x ? i0.x : i0.x - 1, i0.y + 1 < dims.y ? i0.y : i0.y - 1,
                         i0.z + 1 < dims.z ? i0.z : i0.z - 1); /* the last point: the cell below */
        uint b = texelFetch(bricks, c0, 0).x;
        if (b != 0xFFFFFFFFu) {
            int R = refine, S = refine + 1;
            vec3 uf = clamp((f - vec3(c0)) * float(R), vec3(0.0), vec3(float(R)));
            vec3 fl = min(floor(uf), vec3(float(R - 1)));
            vec3 t = uf - fl;
            ivec3 l = ivec3(fl);
            ivec2 bo = ivec2(int(b % uint(atlas_x)), int(b / uint(atlas_x)));
            uint oct = (t.x >= 0.5 ? 1u : 0u) | (t.y >= 0.5 ? 2u : 0u) | (t.z >= 0.5 ? 4u : 0u);
            uvec2 m2 = texelFetch(fine_mask, ivec3(bo * R, 0) + l, 0).xy;
            uint mask = ((oct < 4u ? m2.x : m2.y) >> (8u * (oct & 3u))) & 0xFFu;
            vec3 bor = origin + spacing * vec3(c0); /* the brick's lattice origin */
            vec4 acc[GLOW_SH_PLANES];
            for (int q = 0; q < GLOW_SH_PLANES; ++q) acc[q] = vec4(0.0);
            float wsum = 0.0;
            for (int c = 0; c < 8; ++c) {
                if (((mask >> uint(c)) & 1u) == 0u) continue;
                ivec3 k = l + ivec3(c & 1, (c >> 1) & 1, (c >> 2) & 1);
                float w = ((c & 1) != 0 ? t.x : 1.0 - t.x) * ((c & 2) != 0 ? t.y : 1.0 - t.y) * ((c & 4) != 0 ? t.z : 1.0 - t.z);
                if (!(w > 0.0)) continue;
                if (oriented) {
                    vec3 d = bor + h * vec3(k) - p0;
                    float len = length(d);
                    float hw = len > 0.0 ? 0.5 * (1.0 + dot(d, u) / len) : 1.0;
                    w *= hw * hw + GLOW_GRID_BACKFACE_FLOOR;
                }
                wsum += w;
                ivec3 at = ivec3(bo * S, 0) + k;
                for (int q = 0; q < GLOW_SH_PLANES; ++q) acc[q] += w * texelFetch(fine, at + ivec3(0, 0, q * S), 0);
            }
            if (wsum > 0.0) {
                for (int q = 0; q < GLOW_SH_PLANES; ++q) sh[q] = acc[q] / wsum;
                return true;
            }
        }
    }
    return glow__grid_lookup(grid, grid_mask, origin, spacing, dims, p, p0, oriented, u, sh);
}

/** Bilinear lookup of page `page` of the lightmap at uv in [0,1]² of that page (texel centres at
 * (i + 0.5)/size, v = 0 is row 0), clamped to the page's edge, empty texels weighted 0 and the rest
 * renormalised, as glow.h glow_sample_lightmap_page. The page count and the planes per page follow from
 * the textures' sizes (the valid mask is pages x the lightmap's height; the array pages x planes layers).
 * \returns false when all 4 are empty. */
bool glow_sample_lightmap_page(sampler2DArray lightmap, usampler2D lightmap_valid, int page, vec2 uv,
                               out vec4 sh[GLOW_SH_PLANES]) {
    for (int q = 0; q < GLOW_SH_PLANES; ++q) sh[q] = vec4(0.0);
    ivec3 lsize = textureSize(lightmap, 0);
    ivec2 size = lsize.xy;
    int pages = max(textureSize(lightmap_valid, 0).y / max(size.y, 1), 1);
    int row0 = page * size.y, layer0 = page * (lsize.z / pages);
    vec2 f = clamp(uv * vec2(size) - 0.5, vec2(0.0), vec2(size - 1));
    vec2 fl = floor(f);
    ivec2 i0 = ivec2(fl), i1 = min(i0 + 1, size - 1);
    vec2 t = f - fl;
    float wsum = 0.0;
    for (int c = 0; c < 4; ++c) {
        ivec2 cc = ivec2((c & 1) != 0 ? i1.x : i0.x, (c & 2) != 0 ? i1.y : i0.y);
        float w = ((c & 1) != 0 ? t.x : 1.0 - t.x) * ((c & 2) != 0 ? t.y : 1.0 - t.y);
        if (!(w > 0.0) || texelFetch(lightmap_valid, ivec2(cc.x, cc.y + row0), 0).x == 0u) continue;
        wsum += w;
        for (int q = 0; q < GLOW_SH_PLANES; ++q) sh[q] += w * texelFetch(lightmap, ivec3(cc, layer0 + q), 0);
    }
    if (!(wsum > 0.0)) return false;
    for (int q = 0; q < GLOW_SH_PLANES; ++q) sh[q] /= wsum;
    return true;
}

/** glow_sample_lightmap_page on page 0: the whole lightmap when it has one page. */
bool glow_sample_lightmap(sampler2DArray lightmap, usampler2D lightmap_valid, vec2 uv, out vec4 sh[GLOW_SH_PLANES]) {
    return glow_sample_lightmap_page(lightmap, lightmap_valid, 0, uv, sh);
}

/** glow_sample_lightmap_detail (below) on page `page` of a lightmap of `pages` pages (glow_gl_outputs.lightmap_pages:
 * the detail texture is that many pages high), clamped to the page's edge, as glow.h
 * glow_sample_lightmap_detail_page. */
vec3 glow_sample_lightmap_detail_page(sampler2D detail, int pages, int page, vec2 uv) {
    ivec2 size = textureSize(detail, 0);
    size.y /= max(pages, 1);
    int row0 = page * size.y;
    vec2 f = clamp(uv * vec2(size) - 0.5, vec2(0.0), vec2(size - 1));
    vec2 fl = floor(f);
    ivec2 i0 = ivec2(fl), i1 = min(i0 + 1, size - 1);
    vec2 t = f - fl;
    vec4 acc = vec4(0.0);
    for (int c = 0; c < 4; ++c) {
        ivec2 cc = ivec2((c & 1) != 0 ? i1.x : i0.x, (c & 2) != 0 ? i1.y : i0.y);
        float w = ((c & 1) != 0 ? t.x : 1.0 - t.x) * ((c & 2) != 0 ? t.y : 1.0 - t.y);
        acc += w * texelFetch(detail, ivec2(cc.x, cc.y + row0), 0);
    }
    return acc.w > 1e-6 ? acc.xyz / acc.w : vec3(0.0);
}

/** The lightmap detail (glow_gl_outputs.lightmap_detail_texture, bakes made with glow-bake
 * --lightmap-detail) at uv, the lightmap's UVs: bilinear, clamped to the edge, weighted by coverage (A)
 * and renormalised, as glow.h glow_sample_lightmap_detail. Add it to glow_shade_sh(lightmap sample, n,
 * 1.0) before clamping at 0 and multiplying by the albedo. vec3(0) where no neighbour covers a surface.
 * With several pages: glow_sample_lightmap_detail_page. */
vec3 glow_sample_lightmap_detail(sampler2D detail, vec2 uv) { return glow_sample_lightmap_detail_page(detail, 1, 0, uv); }

#endif /* GLOW_SHADING_GLSL */
