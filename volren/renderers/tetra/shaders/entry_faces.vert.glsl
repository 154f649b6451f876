#version 430
// The boundary faces of the walked cells, drawn as triangles so the rasterizer finds the pixels each
// one covers (entry_faces.geom.glsl grows them a little, entry_faces.frag.glsl lists them there).
// Faces turned away from the eye are dropped.

in vec3 in_position;   // relative to the mesh's centre
in vec4 in_plane;      // the face's inward plane (the walk's, `mesh.glsl`)
in uint in_candidate;  // cell * 8 + face
flat out uint v_candidate;
out float v_facing;  // 1: rays may enter through this face

uniform mat4 u_world_to_clip;
uniform bool u_parallel;
uniform vec3 u_eye;        // perspective: the eye
uniform vec3 u_view_dir;   // parallel: the view direction
uniform float u_tolerance; // world units: closer than this to a plane counts as on it

void main() {
    // rays enter through a face whose inward normal points away from the eye (as the CPU walk's test)
    bool facing = u_parallel ? dot(in_plane.xyz, u_view_dir) >= -1e-7 : dot(in_plane.xyz, u_eye) + in_plane.w <= u_tolerance;
    gl_Position = u_world_to_clip * vec4(in_position, 1.0);
    v_facing = facing ? 1.0 : 0.0;
    v_candidate = in_candidate;
}
