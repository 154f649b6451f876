// The prepared mesh in storage buffers (`gl_walk.py` fills them); the entry lists are in lists.glsl.
// Coordinates are relative to the mesh's centre, so float32 keeps its precision on meshes far
// from the origin. The face planes are the CPU walk's (`traversal.pack_planes`) rounded to float32:
// both cells of a face still hold exactly opposite equations, so one cell's exit parameter is the
// next cell's entry parameter in float32 too.

layout(std430, binding = 0) readonly buffer Planes { vec4 planes[]; };          // 4 per cell: inward unit normal, offset
// Across each face: 4 * the next cell + the index of the same face there; -1: the ray leaves the mesh.
layout(std430, binding = 1) readonly buffer Neighbours { ivec4 neighbours[]; };
// 2 per cell: (gradient, value at corner 0), (corner 0, 1 when the TF gives the cell's value range
// any opacity, else 0).
layout(std430, binding = 2) readonly buffer Fields { vec4 fields[]; };

// |b| at or below this: the ray runs parallel to the face plane (float32 cosines).
const float PARALLEL = 1e-7;

// (a, b) of face f of cell c: the ray o + t d is inside the face's half-space where a + b t >= 0.
vec2 plane_eval(uint c, uint f, vec3 o, vec3 d) {
    vec4 p = planes[4u * c + f];
    return vec2(dot(p.xyz, o) + p.w, dot(p.xyz, d));
}

// Whether a ray lying in face f's plane counts as inside cell c (the CPU walk's symbolic
// perturbation): the first non-zero component of the inward normal is positive.
bool symbolic_inside(uint c, uint f) {
    vec3 n = planes[4u * c + f].xyz;
    if (n.x != 0.0) return n.x > 0.0;
    if (n.y != 0.0) return n.y > 0.0;
    if (n.z != 0.0) return n.z > 0.0;
    return false;
}
