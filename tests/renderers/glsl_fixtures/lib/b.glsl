#include "common.glsl"
#include "helper.glsl"
int b_value() { return COMMON_MARKER + helper(); } // B_MARKER
