#version 430
// One fragment per pixel centre a facing boundary face covers: the face joins that pixel's entry
// list. The rasterizer's fill rule gives a pixel centre on an edge shared by two faces to exactly
// one of them, so no ray between two faces goes without an entry.
#include "lists.glsl"

flat in uint v_candidate;
uniform ivec2 u_size;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);  // GL rows start at the bottom; the lists' at the top
    append(uint((u_size.y - 1 - p.y) * u_size.x + p.x), v_candidate);
}
