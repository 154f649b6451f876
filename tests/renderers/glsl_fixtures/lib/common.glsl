#pragma once
// Shared by a.glsl and b.glsl.
const int COMMON_MARKER = 7;
