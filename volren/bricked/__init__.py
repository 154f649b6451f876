"""Bricked volumes rendered sort-last: cut into bricks, each brick drawn into a premultiplied RGBA
layer by any renderer that draws regions, and the layers composited front to back in the bricks'
visibility order, equal to the whole-volume render.

- `layout`: the bricks of a whole grid, their sub-volumes with ghost voxels and their `Region`s;
- `visibility`: the front-to-back order of the bricks for a camera (a k-d traversal);
- `composite`: the "over" operator on premultiplied layers;
- `source`: where brick values come from (an in-memory volume; an OME-Zarr level);
- `sort_last`: one frame, brick by brick.
"""
