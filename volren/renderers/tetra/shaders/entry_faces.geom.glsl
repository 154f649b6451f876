#version 430
// Each facing face grows by u_margin pixels on every side before the rasterizer sees it, so a pixel
// centre on or just beside an edge lists every face that meets it. (The rasterizer snaps vertices
// to 1/256 pixel and gives a centre on a shared edge to one face only. Where the other face is not
// an entry face, at a silhouette of the walked cells, a ray entering just inside the edge would
// otherwise find no entry: one pixel of oxygen post, smooth TF, at 256x256 lost its whole
// colour that way.) The walk tests every candidate exactly, so extra ones cost a test each.

layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;

flat in uint v_candidate[];
in float v_facing[];
flat out uint g_candidate;

uniform ivec2 u_size;
uniform float u_margin;  // pixels

//: Longest move of a vertex, in margins: a needle-thin triangle's tips move at most this far.
const float MITER_LIMIT = 16.0;

void main() {
    if (v_facing[0] == 0.0) return;
    vec4 clip[3] = vec4[3](gl_in[0].gl_Position, gl_in[1].gl_Position, gl_in[2].gl_Position);
    vec2 half_size = 0.5 * vec2(u_size);
    bool in_front = clip[0].w > 0.0 && clip[1].w > 0.0 && clip[2].w > 0.0;
    vec2 s[3];
    for (int i = 0; i < 3; ++i) s[i] = in_front ? clip[i].xy / clip[i].w * half_size : vec2(0.0);
    float area = (s[1].x - s[0].x) * (s[2].y - s[0].y) - (s[1].y - s[0].y) * (s[2].x - s[0].x);
    if (in_front && area != 0.0) {
        // outward unit normal of edge i (from vertex i to i + 1), in pixels
        vec2 n[3];
        for (int i = 0; i < 3; ++i) {
            vec2 e = s[(i + 1) % 3] - s[i];
            n[i] = length(e) > 0.0 ? sign(area) * normalize(vec2(e.y, -e.x)) : vec2(0.0);
        }
        for (int i = 0; i < 3; ++i) {
            // the corner where both edges at vertex i, moved out by the margin, meet
            vec2 a = n[(i + 2) % 3], b = n[i];
            vec2 miter = (a + b) / max(1.0 + dot(a, b), 1e-6);
            float len = length(miter);
            if (len > MITER_LIMIT) miter *= MITER_LIMIT / len;
            vec2 moved = (s[i] + u_margin * miter) / half_size;
            clip[i] = vec4(moved * clip[i].w, clip[i].zw);
        }
    }
    for (int i = 0; i < 3; ++i) {
        gl_Position = clip[i];
        g_candidate = v_candidate[i];
        EmitVertex();
    }
    EndPrimitive();
}
