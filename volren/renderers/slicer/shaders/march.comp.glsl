#version 430
// The march path: one invocation per pixel walks the same view-aligned sample planes the slice
// path rasterizes, front to back, so it can stop early and jump over empty bricks.
#include "common.glsl"
#include "skipping.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D u_image;
layout(std430, binding = 1) buffer Counters {
    uint samples;      // data values fetched
    uint brick_steps;  // bricks looked at while skipping empty space
    uint terminated;   // rays stopped by early termination
    uint rays_hit;     // rays that met the box
} counters;

uniform mat4 u_clip_to_world;

vec4 pixel_value(vec4 rgba) { return rgba; }
vec4 pixel_value(vec2 value_weight) { return vec4(value_weight, 0.0, 0.0); }
uniform float u_termination;   // accumulated opacity at which a ray stops (> 1: never)

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(u_image);
    if (pixel.x >= size.x || pixel.y >= size.y) return;
    vec2 ndc = (vec2(pixel) + 0.5) / vec2(size) * 2.0 - 1.0;
    vec4 near4 = u_clip_to_world * vec4(ndc, -1.0, 1.0);
    vec4 far4 = u_clip_to_world * vec4(ndc, 1.0, 1.0);
    vec3 origin = near4.xyz / near4.w;
    vec3 dir = far4.xyz / far4.w - origin;
    float t_far = length(dir);
    dir /= t_far;
    vec2 span = box_interval(origin, dir, u_box_min, u_box_max);
    float t0 = max(span.x, 0.0);
    float t1 = min(span.y, t_far);
#if COMPOSITE
    vec4 result = vec4(0.0);
#elif BLEND == 3
    vec2 result = vec2(0.0);
#else
    vec2 result = vec2(NO_DATA, 0.0);
#endif
    if (!(t0 < t1)) {
        imageStore(u_image, pixel, pixel_value(result));
        return;
    }
    // Sample k sits on plane k + jitter: t_k = t_anchor + (k + jitter) dt.
    float cosv = dot(u_view_dir, dir);
    float dt = u_spacing / cosv;
    float t_anchor = (u_plane_base - dot(u_view_dir, origin)) / cosv;
    float jitter = jitter_fraction(uvec2(pixel));
    float k = ceil((t0 - t_anchor) / dt - jitter);   // the first sample plane at or behind the entry
    uint samples = 1u;
    uint skips = 0u;
    float ta = t0;
    float t_stop = t1;
#if COMPOSITE && SKIP
    // Segments whose front lies in an empty brick add nothing: start at the first sample plane
    // in the first non-empty brick and stop after the last one. Keeping the test out of the
    // sample loop matters on llvmpipe, which runs every branch of a divergent loop body.
    vec2 occupied = occupied_span(origin, dir, t0, t1, skips);
    t_stop = occupied.y;
    if (occupied.x > t0) {
        k = ceil((occupied.x - t_anchor) / dt - jitter);
        ta = t_anchor + (k + jitter) * dt;
        k += 1.0;
    }
#endif
    // Pre-integration and the projections read the segment ends (each read once and carried to the
    // next segment); post-classification reads the middle of each segment.
    bool ends = !(COMPOSITE) || PREINTEGRATED == 1;
    vec3 pa = origin + ta * dir;
    float va = ends ? data_value(pa) : 0.0;
    samples = ends ? 1u : 0u;
    while (ta < t_stop) {
        float tb = min(t_anchor + (k + jitter) * dt, t1);
        k += 1.0;
        if (!(tb > ta)) continue;
        vec3 pb = origin + tb * dir;
#if COMPOSITE && PREINTEGRATED == 0
        vec3 pm = origin + (0.5 * (ta + tb)) * dir;
        vec4 c = classify_sample(pm, data_value(pm), tb - ta, dir);
        samples += 1u;
        float vb = 0.0;
#else
        float vb = data_value(pb);
        samples += 1u;
#if COMPOSITE
        vec4 c = classify_segment(pa, pb, va, vb, tb - ta, dir);
#endif
#endif
#if COMPOSITE
        result += (1.0 - result.a) * c;
        if (result.a >= u_termination) {
            atomicAdd(counters.terminated, 1u);
            break;
        }
#else
        vec2 p = project_segment(va, vb, tb - ta);
#if BLEND == 3
        result += p;
#else
        result = max(result, p);
#endif
#endif
        ta = tb;
        pa = pb;
        va = vb;
    }
    atomicAdd(counters.samples, samples);
    atomicAdd(counters.brick_steps, skips);
    atomicAdd(counters.rays_hit, 1u);
    imageStore(u_image, pixel, pixel_value(result));
}
