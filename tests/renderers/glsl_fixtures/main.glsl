#version 430
// Diamond: a.glsl and b.glsl both include common.glsl, which must appear once.
layout(local_size_x = 1) in;
#include "lib/a.glsl"
#include "lib/b.glsl"

void main() {
    int main_marker = a_value() + b_value(); // MAIN_MARKER
}
