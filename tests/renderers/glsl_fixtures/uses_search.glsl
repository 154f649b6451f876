#version 330
#include "only_here.glsl"
void main() {}
