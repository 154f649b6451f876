// The clip region in a shader, shared by the renderers that clip on the GPU (slicer, tetra's GL walk).
const int MAX_CLIP = 12;             // six oblique planes and a crop box's six faces
uniform vec4 u_clip[MAX_CLIP];       // the clip region: kept where dot(xyz, p) + w >= 0 (world)
uniform int u_clip_count;            // rows of u_clip in use; 0: nothing clipped

// `span` (ray parameters) narrowed to the kept side of every clip plane, as
// volren.kernels.clip_planes does on the CPU: the cut lies where the plane is, not on a sample.
vec2 clip_interval(vec3 origin, vec3 dir, vec2 span) {
    for (int i = 0; i < u_clip_count; ++i) {
        float at_origin = dot(u_clip[i].xyz, origin) + u_clip[i].w;
        float rate = dot(u_clip[i].xyz, dir);
        if (rate > 0.0) {
            span.x = max(span.x, -at_origin / rate);
        } else if (rate < 0.0) {
            span.y = min(span.y, -at_origin / rate);
        } else if (at_origin < 0.0) {
            return vec2(1.0, 0.0);
        }
    }
    return span;
}
