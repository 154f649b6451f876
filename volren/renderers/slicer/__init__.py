"""The moderngl view-aligned slicer (Real-Time Volume Graphics, section 3.3): `renderer` (the
`slicer` renderer and its two paths over the same sample planes), `proxy_geometry` (the slice
polygons, numpy), `textures` (what goes to the GPU, numpy) and the GLSL in `shaders/`.
"""
