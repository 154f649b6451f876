#version 430
// The march path: one invocation per pixel walks the same view-aligned sample planes the slice
// path rasterizes, front to back, so it can stop early and jump over empty bricks.
#include "common.glsl"
#include "skipping.glsl"
#include "pixel_ray.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D u_image;
// Per lane: data values fetched, bricks looked at while skipping empty space, rays stopped by
// early termination, rays that met the box. Invocations add to one of STAT_LANES lanes (the host
// sums them): a million rays adding to the same four addresses queue on them.
layout(std430, binding = 1) buffer Counters { uvec4 lanes[]; } counters;
const uint STAT_LANES = 1024u;

// A lane per invocation of a work group, and 16 groups of lanes: neighbouring invocations never
// share an address.
uint stat_lane() {
    uint group = gl_WorkGroupID.x + gl_NumWorkGroups.x * gl_WorkGroupID.y;
    return (gl_LocalInvocationIndex + 64u * group) % STAT_LANES;
}

uniform mat4 u_clip_to_world;

vec4 pixel_value(vec4 rgba) { return rgba; }
vec4 pixel_value(vec2 value_weight) { return vec4(value_weight, 0.0, 0.0); }
uniform float u_termination;   // accumulated opacity at which a ray stops (> 1: never)

uniform ivec2 u_pixel_offset;  // the first pixel of the dispatched rectangle (a brick's: its projection)
uniform ivec2 u_pixel_end;     // and the end of it

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy) + u_pixel_offset;
    ivec2 size = imageSize(u_image);
    if (pixel.x >= u_pixel_end.x || pixel.y >= u_pixel_end.y) return;
    vec2 ndc = (vec2(pixel) + 0.5) / vec2(size) * 2.0 - 1.0;
    vec3 origin, dir;
    float t_far;
    pixel_ray(u_clip_to_world, ndc, origin, dir, t_far);
    vec2 span = box_interval(origin, dir, u_box_min, u_box_max);
    vec2 kept = clip_interval(origin, dir, vec2(max(span.x, 0.0), min(span.y, t_far)));
    float t0 = kept.x;
    float t1 = kept.y;
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
    float ta = t0;            // the front of the next segment; it ends on plane k (+ jitter)
    float t_stop = t1;        // the walk ends here (segments still end at t1 at the latest)
#if REGION
    // A brick draws only the segments it owns (owner point in its half-open box), which lie
    // within one segment of the box: start at the plane just before that and stop one segment
    // after it, on the same planes as the whole render (the planes' anchor is the whole box's).
    vec2 own = box_interval(origin, dir, u_owner_min, u_owner_max);
    t_stop = min(t1, own.y + dt);
    float w0 = own.x - dt;
    if (!(max(t0, w0) < t_stop)) {
        imageStore(u_image, pixel, pixel_value(result));
        return;
    }
    if (w0 > t0) {
        float m = floor((w0 - t_anchor) / dt - jitter);
        float tm = plane_t(t_anchor, m, jitter, dt);
        if (tm > t0) {
            ta = tm;
            k = m + 1.0;
        }
    }
#endif
    uint samples = 0u;
    uint skips = 0u;
    // Pre-integration and the projections read the segment ends (each read once and carried to the
    // next segment); post-classification reads the middle of each segment.
    bool ends = !(COMPOSITE) || PREINTEGRATED == 1;
    precise vec3 pa = origin + ta * dir;
    float va = 0.0;
    bool need_front = ends;   // va must be read at ta
    bool opaque = false;
    // Runs of non-empty bricks along the ray, found by a DDA over the brick grid; a segment whose
    // front lies in an empty brick adds nothing, so the samples jump from one run to the next.
    // The DDA stays out of the sample loop: llvmpipe runs every branch of a divergent loop body.
    while (ta < t_stop && !opaque) {
        float run_end = t_stop;
#if COMPOSITE && SKIP
        float run_start = next_brick_run(origin, dir, ta, t_stop, false, skips);
        if (!(run_start < t_stop)) break;
        if (run_start > ta) {
            k = ceil((run_start - t_anchor) / dt - jitter);
            ta = plane_t(t_anchor, k, jitter, dt);
            k += 1.0;
            if (!(ta < t_stop)) break;
            pa = origin + ta * dir;
            need_front = ends;
        }
        run_end = next_brick_run(origin, dir, ta, t_stop, true, skips);
#endif
        if (need_front) {
            va = data_value(pa);
            samples += 1u;
            need_front = false;
        }
        // At least one segment per run: the DDA and brick_of may disagree about a point on a brick
        // face, and integrating a segment is always safe where skipping one might not be.
        do {
            float tb = min(plane_t(t_anchor, k, jitter, dt), t1);
            k += 1.0;
            if (!(tb > ta)) continue;
            precise vec3 pb = origin + tb * dir;
#if COMPOSITE && PREINTEGRATED == 0
            precise vec3 pm = origin + (0.5 * (ta + tb)) * dir;
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
#if COMPOSITE && REGION
#if PREINTEGRATED
            if (!owned(pa)) c = vec4(0.0);
#else
            if (!owned(pm)) c = vec4(0.0);
#endif
#endif
#if COMPOSITE
            result += (1.0 - result.a) * c;
            if (result.a >= u_termination) {
                opaque = true;
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
        } while (ta < run_end);
    }
    uint lane = stat_lane();
    atomicAdd(counters.lanes[lane].x, samples);
    if (skips > 0u) atomicAdd(counters.lanes[lane].y, skips);
    if (opaque) atomicAdd(counters.lanes[lane].z, 1u);
    atomicAdd(counters.lanes[lane].w, 1u);
    imageStore(u_image, pixel, pixel_value(result));
}
