#version 430

#include "does_not_exist.glsl"
void main() {}
