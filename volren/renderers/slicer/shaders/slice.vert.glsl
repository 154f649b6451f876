#version 330
// Slice polygons and the box's faces, in world coordinates.
in vec3 in_position;
uniform mat4 u_world_to_clip;
out vec3 v_world;

void main() {
    v_world = in_position;
    gl_Position = u_world_to_clip * vec4(in_position, 1.0);
}
