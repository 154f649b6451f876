#version 330
// Early ray termination for the slice path: where the accumulated opacity has reached the
// threshold, write the nearest depth, so the depth test rejects every later slice fragment there.
uniform sampler2D u_accumulated;
uniform float u_termination;
out vec4 unused;

void main() {
    if (texelFetch(u_accumulated, ivec2(gl_FragCoord.xy), 0).a < u_termination) discard;
    unused = vec4(0.0);
}
