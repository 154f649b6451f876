// Shared by the slice (raster) and march (compute) paths: both visit the same sample points and
// classify each segment between them with these functions, so the two paths agree.
//
// Defines (from the renderer): CLASSIFY 0 post-classified 1D TF, 1 pre-integrated 1D TF,
// 2 post-classified 2D TF, 3 label volume (LOOKUP_WIDTH), 4 CHANNELS channels in CHANNEL_TEXTURES textures; SHADE 0/1; BLEND 0 composite, 1 maximum, 2 minimum, 3 average;
// SKIP 0/1 (empty-space skipping by the brick mask); NONFINITE 0/1 (the volume holds NaN or Inf);
// REGION 0/1 (a brick of a bricked render: only the segments it owns, see plane_t and owned).
#pragma once

#define COMPOSITE (BLEND == 0)
#define LUM_LIGHTING (CLASSIFY == 1 && SHADE == 1)
#define NEEDS_GRADIENT (SHADE == 1 || CLASSIFY == 2)
const float NO_DATA = -3.0e38;

uniform sampler3D u_volume;          // the data in its own precision
uniform vec2 u_value_map;            // texel t -> normalised value t * x + y (0 and 1: the data's range)
uniform vec3 u_box_min;              // world bounds of the grid points
uniform vec3 u_box_max;
uniform vec3 u_world_to_tex_scale;   // texture coordinate = world * scale + offset
uniform vec3 u_world_to_tex_offset;
uniform vec3 u_view_dir;             // unit, from the eye into the scene
uniform float u_plane_base;          // view_dir . anchor of the slice planes
uniform float u_spacing;             // distance between slice planes (world)
uniform uint u_jitter_seed;          // 0: no jitter
uniform vec3 u_light;                // L: toward the headlight (-view direction)

// ------------------------------------------------------------------------------ sampling
// Values are normalised: every table covers [0, 1] = the data's finite range.
float data_value(vec3 world) {
    float t = texture(u_volume, world * u_world_to_tex_scale + u_world_to_tex_offset).r;
    return t * u_value_map.x + u_value_map.y;
}

#if NONFINITE
bool is_valid(float v) { return !(isnan(v) || isinf(v)); }
#else
bool is_valid(float v) { return true; }   // the volume has no NaN or Inf: no test per sample
#endif

// Texture coordinate of entry x in [0, 1] of an n-entry table whose entries sit at texel centres.
float table_coord(float x, float n) { return (clamp(x, 0.0, 1.0) * (n - 1.0) + 0.5) / n; }

// A per-pixel fraction in [0, 1) of the slice spacing, the same for a pixel in both paths.
float jitter_fraction(uvec2 pixel) {
    if (u_jitter_seed == 0u) return 0.0;
    uint h = pixel.x * 1973u + pixel.y * 9277u + u_jitter_seed * 26699u;
    h = (h ^ 61u) ^ (h >> 16);
    h *= 9u;
    h ^= h >> 4;
    h *= 0x27d4eb2du;
    h ^= h >> 15;
    return float(h >> 8) / 16777216.0;
}

// Parameter interval of the ray inside the closed box (t0 > t1 when it misses). An axis the ray
// runs parallel to constrains nothing when the ray lies within the slab (the reference's test).
#include "clip_planes.glsl"

vec2 box_interval(vec3 origin, vec3 dir, vec3 lo, vec3 hi) {
    float t_enter = -3.0e38;
    float t_exit = 3.0e38;
    for (int a = 0; a < 3; ++a) {
        if (dir[a] != 0.0) {
            float ta = (lo[a] - origin[a]) / dir[a];
            float tb = (hi[a] - origin[a]) / dir[a];
            t_enter = max(t_enter, min(ta, tb));
            t_exit = min(t_exit, max(ta, tb));
        } else if (origin[a] < lo[a] || origin[a] > hi[a]) {
            return vec2(1.0, 0.0);
        }
    }
    return vec2(t_enter, t_exit);
}

// Where the ray meets sample plane k (+ jitter): computed one way everywhere (`precise`: no
// fused multiply-add in one place and not another), so that every brick of a bricked render
// finds the same sample points as the whole render and as its neighbours.
#if __VERSION__ >= 400
#define PRECISE precise
#else
#define PRECISE          // GLSL 3.30 (the slice path, which draws no bricks) has no `precise`
#endif
float plane_t(float t_anchor, float k, float jitter, float dt) {
    PRECISE float t = t_anchor + (k + jitter) * dt;
    return t;
}

#if REGION
// Sort-last bricks: this brick's own box, half-open; it draws the segments whose owner point
// (the front of a pre-integrated segment, the middle of a post-classified one) lies inside.
uniform vec3 u_owner_min;
uniform vec3 u_owner_max;
bool owned(vec3 p) { return all(greaterThanEqual(p, u_owner_min)) && all(lessThan(p, u_owner_max)); }
#endif

// 1 - exp(-x) without losing the relative precision for thin segments.
float one_minus_exp(float x) {
    return x < 1.0e-3 ? x * (1.0 - x * (0.5 - x / 6.0)) : 1.0 - exp(-x);
}

// --------------------------------------------------------------------------- gradients
#if NEEDS_GRADIENT
uniform sampler3D u_gradient;        // central differences (world units) / u_gradient_scale
uniform float u_gradient_scale;
vec3 gradient_at(vec3 world) {
    return texture(u_gradient, world * u_world_to_tex_scale + u_world_to_tex_offset).xyz * u_gradient_scale;
}
#endif

// ---------------------------------------------------------------------------- shading
#if SHADE
uniform float u_ambient;
uniform float u_diffuse;
uniform float u_specular;
uniform float u_specular_power;
uniform float u_gradient_threshold;  // |grad| at or below this: no shading (DESIGN.md)

// (diffuse factor ka + kd |N.L|, specular ks max(N.H, 0)^p); (1, 0) where there is no gradient.
vec2 light_factors(vec3 g, vec3 half_vector) {
    float magnitude = length(g);
    if (!(magnitude > u_gradient_threshold) || isinf(magnitude)) return vec2(1.0, 0.0);
    vec3 normal = -g / magnitude;
    float ndl = dot(normal, u_light);
    if (ndl < 0.0) {  // two-sided lighting
        normal = -normal;
        ndl = -ndl;
    }
    float ndh = max(dot(normal, half_vector), 0.0);
    float highlight = u_specular_power == 0.0 ? 1.0 : (ndh > 0.0 ? pow(ndh, u_specular_power) : 0.0);
    return vec2(u_ambient + u_diffuse * ndl, u_specular * highlight);
}

vec3 shaded(vec3 colour, vec2 factors) { return clamp(colour * factors.x + factors.y, 0.0, 1.0); }
#endif

// ----------------------------------------------------------------------- classification
#if CLASSIFY == 0
uniform sampler2D u_tf;              // (n, 1): r, g, b, extinction tau per world unit
uniform float u_tf_size;
// Linear interpolation between two texels by hand: half the texel reads of a bilinear lookup.
vec4 tf_lookup(float v) {
    float x = clamp(v, 0.0, 1.0) * (u_tf_size - 1.0);
    int i = min(int(x), int(u_tf_size) - 2);
    return mix(texelFetch(u_tf, ivec2(i, 0), 0), texelFetch(u_tf, ivec2(i + 1, 0), 0), x - float(i));
}
#elif CLASSIFY == 1
uniform sampler2D u_preint;          // [front, back]: premultiplied colour, optical depth (length u_spacing)
uniform float u_preint_size;
#if LUM_LIGHTING
uniform sampler2D u_preint_back;     // [front, back]: diffuse back-weighted, specular back-weighted
#endif
vec2 preint_coord(float front, float back) {
    return vec2(table_coord((back), u_preint_size), table_coord((front), u_preint_size));
}
#elif CLASSIFY == 2
uniform sampler2D u_tf2d;            // (n_values, n_gradients): r, g, b, tau
uniform vec2 u_tf2d_size;
uniform float u_tf2d_gradient_max;
vec4 tf2d_lookup(float v, float gradient_magnitude) {
    return texture(u_tf2d, vec2(table_coord((v), u_tf2d_size.x),
                                table_coord(gradient_magnitude / u_tf2d_gradient_max, u_tf2d_size.y)));
}
#endif

#if CLASSIFY == 3
// Label volumes (Real-Time Volume Graphics, section 16.5; volren.model.labels): a TF per class of
// labels, blended where a cell's corners differ, as raycast's march_labels.label_sample.
const int MIXED = -2;
uniform isampler3D u_cells;          // per cell (at its first corner): the class its corners share, -1, MIXED
uniform usampler3D u_labels;         // per grid point: its label
uniform isampler2D u_lookup;         // label -> class (-1 hidden), LOOKUP_WIDTH labels per row
uniform int u_lookup_count;
uniform sampler2D u_classes;         // (entry, class): r, g, b, extinction tau per world unit
uniform float u_classes_size;
uniform ivec3 u_dims;                // grid points along x, y, z
#elif CLASSIFY == 4
// Multi-channel volumes (volren.model.channels): each drawn channel's TF at its own value, the
// weighted extinctions added (Max 1995), as raycast's march_channels.channel_sample.
uniform sampler3D u_channels0;       // four drawn channels each, normalised over their own ranges
#if CHANNEL_TEXTURES > 1
uniform sampler3D u_channels1;
#endif
#if CHANNEL_TEXTURES > 2
uniform sampler3D u_channels2;
#endif
#if CHANNEL_TEXTURES > 3
uniform sampler3D u_channels3;
#endif
uniform sampler2D u_channel_tables;  // (entry, channel): r, g, b, weighted extinction w tau per world unit
uniform float u_channel_table_size;
#endif

#if CLASSIFY == 3 || CLASSIFY == 4
// Row `row` of a table of n entries over [0, 1], linearly interpolated by hand as tf_lookup.
vec4 row_lookup(sampler2D table, float n, int row, float x01) {
    float x = clamp(x01, 0.0, 1.0) * (n - 1.0);
    int i = min(int(x), int(n) - 2);
    return mix(texelFetch(table, ivec2(i, row), 0), texelFetch(table, ivec2(i + 1, row), 0), x - float(i));
}
#endif

#if CLASSIFY == 3
#define PREINTEGRATED 0
// Premultiplied RGBA of a segment `len` long whose middle `p` has the normalised scalar v: one
// class's entry where the cell's corners share it, else the classes' extinctions weighted by the
// trilinear weights of their corners and the colour weighted by extinction.
vec4 classify_sample(vec3 p, float v, float len, vec3 dir) {
    if (!is_valid(v)) return vec4(0.0);
    vec3 q = (p * u_world_to_tex_scale + u_world_to_tex_offset) * vec3(u_dims) - 0.5;
    ivec3 cell = max(min(ivec3(floor(q)), u_dims - 2), ivec3(0));
    int c0 = texelFetch(u_cells, cell, 0).r;
    if (c0 != MIXED) {
        if (c0 < 0) return vec4(0.0);
        vec4 e = row_lookup(u_classes, u_classes_size, c0, v);
        float alpha = one_minus_exp(e.a * len);
        return vec4(e.rgb * alpha, alpha);
    }
    vec3 f = q - vec3(cell);
    float depth = 0.0;   // tau len, summed over the corners' classes
    vec3 emitted = vec3(0.0);
    for (int k = 0; k < 8; ++k) {
        ivec3 o = ivec3(k & 1, (k >> 1) & 1, k >> 2);
        int label = int(texelFetch(u_labels, cell + o, 0).r);
        if (label >= u_lookup_count) continue;
        int c = texelFetch(u_lookup, ivec2(label % LOOKUP_WIDTH, label / LOOKUP_WIDTH), 0).r;
        if (c < 0) continue;
        vec3 wv = mix(1.0 - f, f, vec3(o));
        float w = wv.x * wv.y * wv.z;
        if (!(w > 0.0)) continue;
        vec4 e = row_lookup(u_classes, u_classes_size, c, v);
        float d = w * e.a;
        depth += d;
        emitted += d * e.rgb;
    }
    if (!(depth > 0.0)) return vec4(0.0);
    float alpha = one_minus_exp(depth * len);
    return vec4(emitted * (alpha / depth), alpha);
}
#elif CLASSIFY == 4
#define PREINTEGRATED 0
// One texture's four channels (from row `first` of the tables) added to depth and emission.
void add_channels(vec4 s, int first, inout float depth, inout vec3 emitted) {
    for (int lane = 0; lane < 4; ++lane) {
        float x = s[lane];
        if (first + lane >= CHANNELS || isnan(x) || isinf(x)) continue;
        vec4 e = row_lookup(u_channel_tables, u_channel_table_size, first + lane, x);
        if (!(e.a > 0.0)) continue;
        depth += e.a;
        emitted += e.a * e.rgb;
    }
}
// Premultiplied RGBA of a segment `len` long whose middle is `p` (the volume's own value v unused).
vec4 classify_sample(vec3 p, float v, float len, vec3 dir) {
    vec3 t = p * u_world_to_tex_scale + u_world_to_tex_offset;
    float depth = 0.0;   // sum of w tau per world unit
    vec3 emitted = vec3(0.0);
    add_channels(texture(u_channels0, t), 0, depth, emitted);
#if CHANNEL_TEXTURES > 1
    add_channels(texture(u_channels1, t), 4, depth, emitted);
#endif
#if CHANNEL_TEXTURES > 2
    add_channels(texture(u_channels2, t), 8, depth, emitted);
#endif
#if CHANNEL_TEXTURES > 3
    add_channels(texture(u_channels3, t), 12, depth, emitted);
#endif
    if (!(depth > 0.0)) return vec4(0.0);
    float alpha = one_minus_exp(depth * len);
    return vec4(emitted * (alpha / depth), alpha);
}
#elif CLASSIFY == 0 || CLASSIFY == 2
#define PREINTEGRATED 0
// Post-classification by the midpoint rule: premultiplied RGBA of a segment `len` world units long
// whose middle is `p` with data value `v` (second order in the step, unlike a sample at the front).
vec4 classify_sample(vec3 p, float v, float len, vec3 dir) {
    if (!is_valid(v)) return vec4(0.0);
#if CLASSIFY == 0
    vec4 e = tf_lookup(v);
#else
    vec3 g2 = gradient_at(p);
    vec4 e = tf2d_lookup(v, length(g2));
#endif
    float alpha = one_minus_exp(e.a * len);
    vec3 colour = e.rgb;
#if SHADE
    vec3 half_vector = normalize(u_light - dir);
#if CLASSIFY == 2
    colour = shaded(colour, light_factors(g2, half_vector));
#else
    colour = shaded(colour, light_factors(gradient_at(p), half_vector));
#endif
#endif
    return vec4(colour * alpha, alpha);
}
#else
#define PREINTEGRATED 1
// Pre-integrated RGBA of the segment [front, back] (`len` world units) along which the data runs
// from vf to vb: the table for the plane spacing, rescaled to the real length (Schulze et al. 2003).
vec4 classify_segment(vec3 front, vec3 back, float vf, float vb, float len, vec3 dir) {
    if (!is_valid(vf) || !is_valid(vb)) return vec4(0.0);
    vec2 tc = preint_coord(vf, vb);
    vec4 entry = texture(u_preint, tc);
    float depth = entry.a;
    float ratio = len / u_spacing;
    float alpha_table = one_minus_exp(depth);
    float alpha = one_minus_exp(depth * ratio);
    float scale = alpha_table > 1.0e-30 ? alpha / alpha_table : ratio;
#if LUM_LIGHTING
    vec3 half_vector = normalize(u_light - dir);
    vec4 back_entry = texture(u_preint_back, tc);
    vec2 lf = light_factors(gradient_at(front), half_vector);
    vec2 lb = light_factors(gradient_at(back), half_vector);
    float specular_back = back_entry.a;
    float specular_front = max(alpha_table - specular_back, 0.0);
    vec3 colour = entry.rgb * lf.x + back_entry.rgb * lb.x + vec3(specular_front * lf.y + specular_back * lb.y);
    return vec4(min(colour * scale, vec3(alpha)), alpha);
#else
    return vec4(entry.rgb * scale, alpha);
#endif
}
#endif

// What a segment contributes to the non-composite blend modes: (value for max / min, weight sum).
// Maximum and minimum use both ends; the average integrates the segment with the trapezoid rule.
vec2 project_segment(float vf, float vb, float len) {
    bool okf = is_valid(vf);
    bool okb = is_valid(vb);
#if BLEND == 3
    if (!okf || !okb) return vec2(0.0, 0.0);
    return vec2(0.5 * (vf + vb) * len, len);
#else
    if (!okf && !okb) return vec2(NO_DATA, 0.0);
    float a = okf ? vf : vb;
    float b = okb ? vb : vf;
#if BLEND == 1
    return vec2(max(a, b), 1.0);
#else
    return vec2(-min(a, b), 1.0);   // minimum as the maximum of -v, so both blend with MAX
#endif
#endif
}
