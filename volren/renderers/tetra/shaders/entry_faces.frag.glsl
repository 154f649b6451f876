#version 430
// One fragment per pixel centre a facing boundary face (grown by entry_faces.geom.glsl) covers: the
// face joins that pixel's entry list.
#include "lists.glsl"

flat in uint g_candidate;
uniform ivec2 u_size;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);  // GL rows start at the bottom; the lists' at the top
    append(uint((u_size.y - 1 - p.y) * u_size.x + p.x), g_candidate);
}
