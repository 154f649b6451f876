// Next to b.glsl: found before the search dir's helper.glsl.
int helper() { return 1; } // HELPER_RELATIVE
