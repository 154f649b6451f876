#version 330
// The slice path: one fragment per (pixel, slice plane k) classifies the ray's segment from plane
// k + jitter to plane k + 1 + jitter, clipped to the box and the clip region. The polygons are cut from a box grown by
// two plane spacings along the ray, so the planes just before the box own the segment from where
// the ray enters to its first plane, and no pixel depends on rasterizing a polygon edge exactly.
// Blending is front to back ("under") for composite, MAX for maximum and minimum (-v), ADD for
// the average.
#include "common.glsl"
#if SKIP
#include "skipping.glsl"
#endif

in vec3 v_world;
out vec4 frag;

uniform vec3 u_eye;
uniform bool u_perspective;

void main() {
    vec3 dir = u_perspective ? normalize(v_world - u_eye) : u_view_dir;
    float cosv = dot(u_view_dir, dir);
    float dt = u_spacing / cosv;
    float jitter = jitter_fraction(uvec2(gl_FragCoord.xy));
    float plane = (dot(u_view_dir, v_world) - u_plane_base) / u_spacing;
    // Ray parameters relative to this fragment's point.
    float ta = (round(plane) + jitter - plane) * dt;
    float tb = ta + dt;
    vec2 inside = clip_interval(v_world, dir, box_interval(v_world, dir, u_box_min, u_box_max));
    ta = max(ta, inside.x);
    tb = min(tb, inside.y);
    if (!(tb > ta)) discard;
    vec3 pa = v_world + ta * dir;
    vec3 pb = v_world + tb * dir;
#if COMPOSITE && SKIP
    if (brick_empty(brick_of(pa))) discard;
#endif
#if COMPOSITE && PREINTEGRATED == 0
    vec3 pm = 0.5 * (pa + pb);
    frag = classify_sample(pm, data_value(pm), tb - ta, dir);
#elif COMPOSITE
    frag = classify_segment(pa, pb, data_value(pa), data_value(pb), tb - ta, dir);
#else
    frag = vec4(project_segment(data_value(pa), data_value(pb), tb - ta), 0.0, 0.0);
#endif
}
