// Includes cycle_a.glsl back: a cycle.
#include "cycle_a.glsl"
