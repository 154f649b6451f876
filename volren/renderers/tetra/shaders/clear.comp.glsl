#version 430
// Empties every pixel's entry list before the faces are binned again.
layout(local_size_x = 256) in;
layout(std430, binding = 4) writeonly buffer Counts { uint counts[]; };
uniform uint u_count;

void main() {
    uint i = gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 256u + gl_GlobalInvocationID.x;
    if (i < u_count) counts[i] = 0u;
}
