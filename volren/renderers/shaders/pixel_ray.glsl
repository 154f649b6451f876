// The ray through a point of the image given in normalized device coordinates: its origin on the
// near plane, its unit direction and the distance to the far plane, through the inverse of the
// camera's projection times view matrix. Shared by the ray casters (each maps pixels to NDC with
// its own row order).
void pixel_ray(mat4 clip_to_world, vec2 ndc, out vec3 origin, out vec3 dir, out float t_far) {
    vec4 near4 = clip_to_world * vec4(ndc, -1.0, 1.0);
    vec4 far4 = clip_to_world * vec4(ndc, 1.0, 1.0);
    origin = near4.xyz / near4.w;
    dir = far4.xyz / far4.w - origin;
    t_far = length(dir);
    dir /= t_far;
}
