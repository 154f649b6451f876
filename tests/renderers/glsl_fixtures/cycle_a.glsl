#version 430
#include "cycle_b.glsl"
void main() {}
