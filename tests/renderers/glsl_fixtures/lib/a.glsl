#include "common.glsl"
int a_value() {
    return COMMON_MARKER + 1; // A_MARKER
}
