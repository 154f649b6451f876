// Empty-space skipping: a brick is "empty" when its TF opacity is zero over the value range of
// itself and its neighbours (see the renderer's brick classification), so every segment whose
// front lies in it contributes nothing, even a pre-integrated one reaching into a neighbour.
#pragma once

uniform sampler3D u_brick_mask;      // 1 = empty (skip), nearest filtering, one texel per brick
uniform vec3 u_brick_origin;         // world position of the first grid point
uniform vec3 u_brick_size;           // world extent of one brick
uniform ivec3 u_brick_count;

ivec3 brick_of(vec3 world) {
    return clamp(ivec3(floor((world - u_brick_origin) / u_brick_size)), ivec3(0), u_brick_count - 1);
}

bool brick_empty(ivec3 b) { return texelFetch(u_brick_mask, b, 0).r >= 0.5; }

// Walk the bricks along origin + t dir from t_from (3D DDA, Amanatides and Woo) and return the
// t where the first brick that is empty (`want_empty`) or not empty begins: t_from itself when the
// brick there already is, t_to when none begins before it. `steps` counts the bricks looked at.
float next_brick_run(vec3 origin, vec3 dir, float t_from, float t_to, bool want_empty, inout uint steps) {
    ivec3 b = brick_of(origin + t_from * dir);
    ivec3 stride = ivec3(sign(dir));
    vec3 lo = u_brick_origin + vec3(b) * u_brick_size;
    vec3 boundary = lo + vec3(greaterThan(dir, vec3(0.0))) * u_brick_size;
    vec3 t_max = vec3(1.0e30);
    vec3 t_delta = vec3(1.0e30);
    for (int a = 0; a < 3; ++a) {
        if (dir[a] != 0.0) {
            t_max[a] = (boundary[a] - origin[a]) / dir[a];
            t_delta[a] = u_brick_size[a] / abs(dir[a]);
        }
    }
    float t = t_from;
    for (int i = 0; i < 4096; ++i) {
        steps += 1u;
        if (brick_empty(b) == want_empty) return t;
        float t_next = min(t_max.x, min(t_max.y, t_max.z));
        if (t_next >= t_to) return t_to;
        t = max(t_next, t_from);
        if (t_max.x <= t_max.y && t_max.x <= t_max.z) {
            b.x += stride.x;
            t_max.x += t_delta.x;
        } else if (t_max.y <= t_max.z) {
            b.y += stride.y;
            t_max.y += t_delta.y;
        } else {
            b.z += stride.z;
            t_max.z += t_delta.z;
        }
        if (any(lessThan(b, ivec3(0))) || any(greaterThanEqual(b, u_brick_count))) return t_to;
    }
    return want_empty ? t_to : t_from;  // not expected; skipping nothing is always safe
}
