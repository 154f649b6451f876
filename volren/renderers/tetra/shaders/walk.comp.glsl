#version 430
// The GPU walk: one invocation per pixel ray does what the CPU's `traversal.cast_rays` does, in
// float32. It takes the entries from its pixel's list (`entry_faces.*.glsl`, `bin_near.comp.glsl`) in order of their
// ray parameter, walks from each one from cell to cell through the exit faces until the ray leaves
// the mesh, and integrates each cell segment with the 3D pre-integration table.
//
// Entries are found lazily: the next one is the smallest (t, candidate) after the last one walked
// and not behind where the last walk ended, so a ray needs no sorted array of its own (registers
// are what a GPU has least of) and each candidate is walked at most once.
//
// Defines: BLEND (0 composite, 1 maximum, 2 minimum, 3 average), SHADE (0/1), JUMP (1: the entry
// faces are those of the visible cells, and a walk ends where it would run through a transparent
// cell, so the next entry skips the transparent run; it still steps around an edge or a vertex
// through any cell at zero length).
#define LIST_ACCESS readonly
#define LISTS_READ_ONLY 1
#include "mesh.glsl"
#include "lists.glsl"
#include "pixel_ray.glsl"
#include "clip_planes.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, binding = 11) writeonly buffer Result { vec4 result[]; };  // row 0 at the top

// x: back value, y: front value, z: length layer; rgb: colour per unit opacity, a: optical depth
// per unit length (the same in every layer).
uniform sampler3D u_table;
uniform mat4 u_clip_to_world;
uniform ivec2 u_size;
uniform float u_lo;          // table index = (value - u_lo) * u_scale
uniform float u_scale;
uniform float u_lmax;        // the length of the last layer
uniform float u_tolerance;   // world units: closer than this to a plane counts as on it
uniform float u_termination; // opacity at which a ray stops (> 1: never)
uniform uint u_max_steps;    // most cells one walk may take
uniform vec4 u_phong;        // ambient, diffuse, specular, specular power
uniform float u_gradient_threshold;
uniform vec3 u_light;        // unit vector towards the light

const float FAR = 3.0e38;

// The ray parameter where candidate `key` lets the ray into the mesh, or -1 where it does not: 0
// where the ray starts inside the cell; else where it crosses the named boundary face heading
// inwards, before t_max, inside the face's triangle (within float32 rounding, u_tolerance). The
// faces were rasterized grown by a margin (entry_faces.geom.glsl), so every face the ray crosses
// is listed, also at an edge, and a list may hold faces the ray just misses.
float entry_parameter(uint key, vec3 o, vec3 d, float t_max) {
    uint cell = key >> 3u;
    uint code = key & 7u;
    vec2 ab[4];
    bool inside = true;
    for (uint f = 0u; f < 4u; ++f) {
        ab[f] = plane_eval(cell, f, o, d);
        if (ab[f].x < -u_tolerance) inside = false;
    }
    if (inside) return 0.0;
    if (code == NEAR_CELL || !(ab[code].y > PARALLEL)) return -1.0;
    float t = -ab[code].x / ab[code].y;
    if (!(t >= 0.0 && t <= t_max)) return -1.0;
    for (uint g = 0u; g < 4u; ++g)
        if (g != code && ab[g].x + ab[g].y * t < -u_tolerance) return -1.0;
    return t;
}

// The table, bilinear within the texel square at `at`: w.x the back value's fraction, w.y the front's.
vec4 bilinear(ivec3 at, vec2 w) {
    vec4 t00 = texelFetch(u_table, at, 0);
    vec4 t01 = texelFetch(u_table, at + ivec3(1, 0, 0), 0);
    vec4 t10 = texelFetch(u_table, at + ivec3(0, 1, 0), 0);
    vec4 t11 = texelFetch(u_table, at + ivec3(1, 1, 0), 0);
    return mix(mix(t00, t01, w.x), mix(t10, t11, w.x), w.y);
}

// A lane per invocation of a work group, and 16 groups of lanes: neighbouring invocations never
// share an address.
uint stat_lane() {
    uint group = gl_WorkGroupID.x + gl_NumWorkGroups.x * gl_WorkGroupID.y;
    return (gl_LocalInvocationIndex + 64u * group) % STAT_LANES;
}

// 1 - exp(-depth), without float32's cancellation for thin segments.
float opacity_of_depth(float depth) {
    return depth < 1e-3 ? depth * (1.0 - depth * (0.5 - depth / 6.0)) : 1.0 - exp(-depth);
}

// Premultiplied RGBA of a segment (`traversal.integrate_segment`): the optical depth is exact in the
// length, the colour per unit opacity linear between length layers.
vec4 integrate_segment(float s_front, float s_back, float len) {
    ivec3 size = textureSize(u_table, 0);
    float n = float(size.x);
    float x = clamp((s_front - u_lo) * u_scale, 0.0, n - 1.0);
    float y = clamp((s_back - u_lo) * u_scale, 0.0, n - 1.0);
    int i0 = min(int(x), size.x - 2);
    int j0 = min(int(y), size.x - 2);
    vec2 w = vec2(y - float(j0), x - float(i0));
    float layers = float(size.z);
    float u = clamp(layers * len / u_lmax - 1.0, 0.0, layers - 1.0);
    int k0 = min(int(u), size.z - 1);
    int k1 = min(k0 + 1, size.z - 1);
    vec4 near_layer = bilinear(ivec3(j0, i0, k0), w);
    float alpha = opacity_of_depth(len * near_layer.a);
    vec3 ratio = mix(near_layer.rgb, bilinear(ivec3(j0, i0, k1), w).rgb, u - float(k0));
    return vec4(ratio * alpha, alpha);
}

// (diffuse factor, specular term) for a cell's constant gradient; (1, 0) without one.
vec2 shade_factors(vec3 gradient, vec3 half_vector) {
    float mag = length(gradient);
    if (!(mag > u_gradient_threshold) || isinf(mag)) return vec2(1.0, 0.0);
    vec3 normal = -gradient / mag;
    float ndl = dot(normal, u_light);
    if (ndl < 0.0) {
        normal = -normal;
        ndl = -ndl;
    }
    float ndh = max(dot(normal, half_vector), 0.0);
    return vec2(u_phong.x + u_phong.y * ndl, ndh > 0.0 ? u_phong.z * pow(ndh, u_phong.w) : 0.0);
}

vec4 cast_ray(ivec2 pixel) {
    uint list = uint(pixel.y * u_size.x + pixel.x);
    uint count = min(counts[list], u_slots);
    if (count == 0u) return vec4(0.0);
    list *= u_slots;
    vec2 ndc = vec2((float(pixel.x) + 0.5) / float(u_size.x) * 2.0 - 1.0,
                    1.0 - (float(pixel.y) + 0.5) / float(u_size.y) * 2.0);
    vec3 o, d;
    float t_max;
    pixel_ray(u_clip_to_world, ndc, o, d, t_max);
    // the part of the ray the clip region keeps: the walk ends at its exit, segments start at its entry
    vec2 keep = clip_interval(o, d, vec2(0.0, t_max));
    if (!(keep.y > keep.x)) return vec4(0.0);
    t_max = keep.y;
    vec3 h = u_light - d;
    h = dot(h, h) > 0.0 ? normalize(h) : h;

    vec3 colour = vec3(0.0);
    float trans = 1.0;
    float best = 0.0;    // maximum / minimum: the value so far
    bool found = false;  // projections: the ray met data
    float integral = 0.0;
    float total = 0.0;
    uint steps = 0u;
    uint integrated = 0u;
    uint cut = 0u;

    float t_done = -FAR;
    float last_t = -FAR;
    uint last_key = 0u;
    bool have_last = false;
    bool done = false;
    while (!done) {
        float t_in = FAR;
        uint key = 0u;
        for (uint i = 0u; i < count; ++i) {
            uint candidate = slots[list + i];
            float t0 = entry_parameter(candidate, o, d, t_max);
            if (t0 < 0.0 || t0 < t_done - u_tolerance) continue;
            if (have_last && (t0 < last_t || (t0 == last_t && candidate <= last_key))) continue;
            if (t0 < t_in || (t0 == t_in && candidate < key)) {
                t_in = t0;
                key = candidate;
            }
        }
        if (t_in == FAR) break;
        have_last = true;
        last_t = t_in;
        last_key = key;

        uint c = key >> 3u;
        uint entered_by = key & 7u;  // the face the ray came in through (NEAR_CELL: none)
        vec4 field = fields[2u * c];
        float s_in = field.w + dot(field.xyz, o + t_in * d - fields[2u * c + 1u].xyz);
        float t_out = t_in;
        for (uint walked = 1u;; ++walked) {
            // the exit: the first face plane the ray heads out of; a ray lying in a face plane that
            // the perturbation puts outside this cell leaves through it at once
            float t_exit = FAR;
            int face = -1;
            for (uint f = 0u; f < 4u; ++f) {
                if (f == entered_by) continue;  // the ray heads in through it (its plane is the last cell's exit)
                vec2 ab = plane_eval(c, f, o, d);
                if (ab.y < -PARALLEL) {
                    float t = -ab.x / ab.y;
                    if (t < t_exit) {
                        t_exit = t;
                        face = int(f);
                    }
                } else if (ab.y <= PARALLEL && abs(ab.x) <= u_tolerance && !symbolic_inside(c, f)) {
                    t_exit = t_in;
                    face = int(f);
                    break;
                }
            }
            if (face < 0) {
                t_out = t_in;
                break;
            }
            t_out = min(max(t_exit, t_in), t_max);
            bool visible = fields[2u * c + 1u].w != 0.0;
#if JUMP
            // a transparent cell the ray runs through (not just around an edge): the walk ends
            if (t_out > t_in && !visible) {
                t_out = t_in;
                break;
            }
#endif
            vec3 gradient = fields[2u * c].xyz;
            float slope = dot(gradient, d);
            float s_out = s_in + slope * (t_out - t_in);
            float t_kept = max(t_in, keep.x);  // a segment across the clip region's entry: its kept part
            float s_kept = t_kept > t_in ? s_in + slope * (t_kept - t_in) : s_in;
            float len = t_out - t_kept;
            steps += 1u;
            if (len > 0.0) {
#if BLEND == 0
                if (visible) {
                    vec4 rgba = integrate_segment(s_kept, s_out, len);
#if SHADE
                    vec2 k = shade_factors(gradient, h);
                    rgba.rgb = min(rgba.rgb * k.x + k.y * rgba.a, vec3(rgba.a));
#endif
                    colour += trans * rgba.rgb;
                    trans *= 1.0 - rgba.a;
                    integrated += 1u;
                    if (1.0 - trans >= u_termination) {
                        done = true;
                        break;
                    }
                }
#elif BLEND == 3
                integral += 0.5 * (s_kept + s_out) * len;
                total += len;
                found = true;
#else
                float v = BLEND == 1 ? max(s_kept, s_out) : min(s_kept, s_out);
                if (!found || (BLEND == 1 && v > best) || (BLEND == 2 && v < best)) best = v;
                found = true;
#endif
            }
            if (t_out >= t_max) {
                done = true;
                break;
            }
            int next = neighbours[c][face];  // 4 * cell + its matching face
            if (next < 0) break;
            if (walked >= u_max_steps) {
                cut += 1u;
                break;
            }
            c = uint(next) >> 2u;
            entered_by = uint(next) & 3u;
            t_in = t_out;
            s_in = s_out;
        }
        t_done = t_out;
    }
    // Counted per ray in global memory, spread over lanes. (Summing per work group in shared
    // memory first needs two barrier() calls, which made every frame 11x slower on an H100.)
    if (steps > 0u) {
        uint lane = stat_lane();
        atomicAdd(counters.work[lane].x, steps);
        atomicAdd(counters.work[lane].y, integrated);
        if (cut > 0u) atomicAdd(counters.work[lane].z, cut);
        atomicAdd(counters.work[lane].w, 1u);
    }
#if BLEND == 0
    return vec4(colour, 1.0 - trans);
#elif BLEND == 3
    return found ? vec4(integral / total, 1.0, 0.0, 0.0) : vec4(0.0);
#else
    return found ? vec4(best, 1.0, 0.0, 0.0) : vec4(0.0);
#endif
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (pixel.x < u_size.x && pixel.y < u_size.y) result[pixel.y * u_size.x + pixel.x] = cast_ray(pixel);
}
