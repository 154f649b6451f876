"""The hierarchical occlusion map: which screen regions no longer let anything through.

Why: object order has no early ray termination of its own; Mora et al. (section 4.2, after Zhang et
al.'s HOMs) keep a pyramid over the image, updated as pixels saturate, and skips an octree node
whose footprint lies on saturated pixels only. Here level m counts the *finished* pixels of each
2^m x 2^m block of one band of rows: a pixel is finished when its opacity reached the termination
opacity, or when its ray has no sample left (rays that miss the volume are finished from the
start, so silhouettes do not keep blocks open). A block is full when its count is 4^m (pixels
outside the band count as finished). The test for a footprint (a pixel rectangle) reads the
finest level on which it spans at most 4 x 4 blocks, all of which must be full. It is conservative:
a node is skipped only when every pixel of its footprint is finished, and the blocks round the
footprint out by less than a quarter of its size (a leaf cell's few pixels are read one by one).
Reading the level whose blocks are as large as the footprint (2 x 2 blocks) instead rounds a 3 x 3
pixel footprint out to 8 x 8 and lets thin opaque structures (the aneurism's vessels) hide little.

All functions work on one flat int32 array per band: level m at offsets[m], `cols[m]` blocks per row.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(nogil=True, cache=True)
def hom_layout(rows: int, cols: int):
    """(levels, offsets, block columns per level, size) for a rows x cols band."""
    levels = 1
    while (1 << (levels - 1)) < max(rows, cols):
        levels += 1
    offsets = np.zeros(levels + 1, np.int64)
    ncols = np.zeros(levels, np.int64)
    for m in range(levels):
        r = (rows + (1 << m) - 1) >> m
        c = (cols + (1 << m) - 1) >> m
        ncols[m] = c
        offsets[m + 1] = offsets[m] + r * c
    return levels, offsets, ncols, offsets[levels]


@njit(nogil=True, cache=True)
def hom_init(hom, levels, offsets, ncols, rows, cols):
    """Every block starts with its pixels outside the band counted as finished."""
    for m in range(levels):
        size = 1 << m
        nr = (rows + size - 1) >> m
        for br in range(nr):
            h = min(rows, (br + 1) * size) - br * size
            for bc in range(ncols[m]):
                w = min(cols, (bc + 1) * size) - bc * size
                hom[offsets[m] + br * ncols[m] + bc] = size * size - h * w


@njit(nogil=True, cache=True)
def hom_finish(hom, levels, offsets, ncols, r, c):
    """Pixel (r, c) of the band (band-local row) is finished: count it at every level."""
    for m in range(levels):
        hom[offsets[m] + (r >> m) * ncols[m] + (c >> m)] += 1


@njit(nogil=True, cache=True)
def hom_covered(hom, levels, offsets, ncols, r0, r1, c0, c1):
    """True when every pixel of rows r0..r1, columns c0..c1 (inclusive, band-local) is finished."""
    m = 0
    while m < levels - 1 and max((r1 >> m) - (r0 >> m), (c1 >> m) - (c0 >> m)) >= 4:
        m += 1
    full = 1 << (2 * m)
    for br in range(r0 >> m, (r1 >> m) + 1):
        for bc in range(c0 >> m, (c1 >> m) + 1):
            if hom[offsets[m] + br * ncols[m] + bc] < full:
                return False
    return True
