"""The moderngl view-aligned slicer (Real-Time Volume Graphics, section 3.3): this package will hold
a renderer that draws the volume as a stack of polygons perpendicular to the viewing direction,
textured from a 3D texture and blended back to front, with the polygons computed on the CPU by
`proxy_geometry`.
"""
