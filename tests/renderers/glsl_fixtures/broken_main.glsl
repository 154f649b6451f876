#version 430
layout(local_size_x = 1) in;
#include "lib/broken.glsl"
void main() {
    int y = broken();
}
