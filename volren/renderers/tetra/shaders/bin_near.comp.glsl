#version 430
// The cells the near plane cuts join the entry lists of every pixel of their projected boxes: rays
// may start inside them (the eye is in the mesh). The walk tests each one exactly.
#include "lists.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 9) readonly buffer NearBoxes { ivec4 near_boxes[]; };  // (x0, x1, y0, y1) of near_cells[i]
layout(std430, binding = 10) readonly buffer NearCells { uint near_cells[]; };

uniform ivec2 u_size;
uniform uint u_near_count;

void main() {
    uint k = gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u + gl_GlobalInvocationID.x;
    if (k >= u_near_count) return;
    ivec4 box = near_boxes[k];
    for (int y = box.z; y <= box.w; ++y)
        for (int x = box.x; x <= box.y; ++x) append(uint(y * u_size.x + x), near_cells[k] * 8u + NEAR_CELL);
}
