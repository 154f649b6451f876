/* A comment may come before #version.
   #include "not_an_include.glsl" is ignored in comments. */
#version 430
layout(local_size_x = 1) in;
layout(std430, binding = 0) buffer Out { int result[]; };
void main() {
    result[0] = VALUE;
    result[1] = FLAG;
    result[2] = int(SCALE * 2.0);
}
