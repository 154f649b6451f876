"""What the slicer uploads, prepared in numpy: the volume in its own precision, its gradients and
the transfer-function tables. No GL here, so all of it is tested without a context.

Why the normalised value axis: the shaders work with x = (v - lo) / (hi - lo) over the data's
finite value range [lo, hi], and every table covers exactly that range. In float32 a data value
like 1e6 + 0.3 cannot be turned into a table coordinate without cancellation, and a float64 volume
cannot be uploaded at all; both are normalised in float64 on the CPU instead (and so is integer
data, see `volume_texture`). A per-volume affine map in the shader turns the texel into x. The TF is constant beyond its ends and trilinear values never leave [lo, hi], so
tables over [lo, hi] are exact for every segment a renderer can meet.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from volren.model.preintegration import lighting_tables, preintegrate
from volren.model.transfer_function import TransferFunction1D
from volren.model.volume import UniformVolume

#: Entries of the post-classification TF texture: enough that a spike of 1/1000 of the range
#: spans several texels.
POST_TF_SIZE = 4096


@dataclass(frozen=True, eq=False)
class VolumeTexture:
    """The volume as texel data: `data` (nz, ny, nx) in `dtype` (a moderngl dtype), and the map
    x = texel * value_map[0] + value_map[1] from what the shader reads to the normalised value."""

    data: NDArray
    dtype: str
    value_map: tuple[float, float]
    lo: float
    hi: float

    def to_data_value(self, x: NDArray) -> NDArray[np.float64]:
        """Normalised values back to data units (float64)."""
        return self.lo + np.asarray(x, dtype=np.float64) * (self.hi - self.lo)


def value_range(volume: UniformVolume, whole: tuple[float, float] | None = None) -> tuple[float, float]:
    """The range the tables cover: the finite data range (`whole`: the whole volume's, for a
    brick), widened when it is a single value."""
    lo, hi = whole if whole is not None else volume.value_range
    return value_range_of((lo, hi))


#: Integers in this range are exact in a half float, and llvmpipe filters half floats in float32.
HALF_EXACT = 2048


def volume_texture(
    volume: UniformVolume, native: bool = False, whole: tuple[float, float] | None = None
) -> VolumeTexture:
    """The texel data for `volume`:
    - integer data within +-2048 (all 8-bit data): its own values as half floats, exact, half the
      memory of float32 (and faster to filter on llvmpipe);
    - anything else: normalised to [0, 1] in float64 and stored as float32 (NaN/Inf kept);
    - with `native`, 8-bit data as an 8-bit normalised texture instead.

    Why not 8-bit and 16-bit normalised textures throughout: Mesa llvmpipe filters 8-bit textures
    in 8-bit arithmetic, so every trilinear value is rounded to a whole data step (measured: up to
    1.1 steps off, 0.34 on average, against 1.4e-4 for half and 7e-5 for float32), which
    pre-integration, made to follow the data between samples exactly, cannot afford; and its
    16-bit normalised 3D textures filter wrongly (values off by tens of steps). GPUs filter 8-bit
    data to float with 8-bit weights, where `native` saves half the memory again.
    `whole` is the whole volume's value range when `volume` is one brick of it.
    """
    lo, hi = value_range(volume, whole)
    span = hi - lo
    values = volume.values
    if native and values.dtype == np.uint8:
        return VolumeTexture(values, "f1", (255.0 / span, -lo / span), lo, hi)
    if np.issubdtype(values.dtype, np.integer) and -HALF_EXACT <= lo and hi <= HALF_EXACT:
        return VolumeTexture(values.astype(np.float16), "f2", (1.0 / span, -lo / span), lo, hi)
    normalised = np.empty(values.shape, dtype=np.float32)
    np.multiply(np.subtract(values, lo, dtype=np.float64), 1.0 / span, out=normalised, casting="same_kind")
    return VolumeTexture(normalised, "f4", (1.0, 0.0), lo, hi)


def gradient_texture(
    volume: UniformVolume, whole: tuple[float, float] | None = None
) -> tuple[NDArray[np.float16], float]:
    """Central differences in world units at the grid points, one-sided at the borders (the
    reference's gradient), as half floats (nz, ny, nx, 3) divided by the returned scale (from the
    value range: `whole`, the whole volume's, for a brick, so every brick rounds alike)."""
    values = volume.values
    lo, hi = whole if whole is not None else volume.value_range
    span = float(hi - lo) or 1.0
    scale = span / min(volume.spacing)  # the largest |d s / d axis| one cell can give
    out = np.empty(values.shape + (3,), dtype=np.float16)
    for axis, h in ((2, volume.spacing[0]), (1, volume.spacing[1]), (0, volume.spacing[2])):
        component = np.gradient(values.astype(np.float32, copy=False), axis=axis) / np.float32(h * scale)
        out[..., 2 - axis] = component
    return out, scale


def post_tf_table(tf: TransferFunction1D, lo: float, hi: float, n: int = POST_TF_SIZE) -> NDArray[np.float32]:
    """(1, n, 4): colour and extinction tau per world unit at lo + (hi - lo) k / (n - 1)."""
    values = np.linspace(lo, hi, n)
    rgb, _ = tf.sample(values)
    tau = tf.extinction(values)
    return np.concatenate([rgb, tau[:, None]], axis=1).astype(np.float32)[None]


def tf2d_table(tf, lo: float, hi: float, n_values: int = 512, n_gradients: int = 256) -> NDArray[np.float32]:
    """(n_gradients, n_values, 4): colour and extinction tau of a 2D TF at data values
    lo + (hi - lo) i / (n_values - 1) and gradient magnitudes gmax j / (n_gradients - 1)."""
    values = np.linspace(lo, hi, n_values)[None, :]
    gradients = np.linspace(0.0, tf.gradient_range[1], n_gradients)[:, None]
    rgb, _ = tf.sample(values, gradients)
    tau = tf.extinction(values, gradients)
    return np.concatenate([rgb, tau[..., None]], axis=-1).astype(np.float32)


def _optical_depth(alpha: NDArray) -> NDArray[np.float64]:
    return -np.log1p(-np.minimum(alpha.astype(np.float64), 1.0 - 1e-7))


def preintegration_table(
    tf: TransferFunction1D, lo: float, hi: float, n: int, spacing: float
) -> NDArray[np.float32]:
    """(n, n, 4) [front, back]: premultiplied colour and the optical depth -ln(1 - alpha) of a
    segment `spacing` long. The shader rescales both to the segment's real length (Schulze et al. 2003's
    opacity and colour correction), exactly for the opacity."""
    table = preintegrate(tf, n, step=spacing, value_range=(lo, hi))
    out = np.array(table, dtype=np.float32)
    out[..., 3] = _optical_depth(table[..., 3])
    return out


def lighting_textures(
    tf: TransferFunction1D, lo: float, hi: float, n: int, spacing: float
) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """Lum et al.'s front table (diffuse front-weighted, optical depth) and back table (diffuse
    back-weighted, specular back-weighted), both (n, n, 4)."""
    tables = lighting_tables(tf, n, step=spacing, value_range=(lo, hi))
    front = np.array(tables.front, dtype=np.float32)
    front[..., 3] = _optical_depth(tables.front[..., 3])
    return front, np.array(tables.back, dtype=np.float32)


#: Labels per row of the label -> class lookup texture (a 2D texture: 65536 labels exceed the
#: width of a 1D one on many drivers).
LOOKUP_WIDTH = 1024
#: Bytes the per-class tables may take together: many classes share it, fewer entries each.
LABEL_TABLES_BYTES = 64 << 20


def label_lookup(lookup: NDArray[np.int32]) -> NDArray[np.int32]:
    """(rows, LOOKUP_WIDTH) label -> class (`LabelClasses.lookup`), -1 (hidden) past its end."""
    rows = -(-len(lookup) // LOOKUP_WIDTH)
    out = np.full(rows * LOOKUP_WIDTH, -1, np.int32)
    out[: len(lookup)] = lookup
    return out.reshape(rows, LOOKUP_WIDTH)


def class_table_size(n_classes: int, n: int = POST_TF_SIZE) -> int:
    """Entries per class table: `n`, fewer where many classes would outgrow LABEL_TABLES_BYTES."""
    return max(16, min(n, LABEL_TABLES_BYTES // (16 * max(n_classes, 1))))


def class_tables(tfs: Sequence[TransferFunction1D], lo: float, hi: float, n: int) -> NDArray[np.float32]:
    """(classes, n, 4): each class's colour and extinction tau per world unit at lo + (hi - lo) k / (n - 1),
    the rows of `post_tf_table`; one zero row where no class draws."""
    out = np.zeros((max(len(tfs), 1), n, 4), np.float32)
    for c, tf in enumerate(tfs):
        out[c] = post_tf_table(tf, lo, hi, n)[0]
    return out


def channel_textures(values: NDArray, ranges: Sequence[tuple[float, float]]) -> NDArray[np.float32]:
    """Up to four drawn channels `values` (c, nz, ny, nx) as one RGBA float32 texture (nz, ny, nx, 4),
    each normalised over its own finite range (`value_range_of`; NaN and Inf kept), as the volume is:
    every table then covers [0, 1]. Unused lanes hold 0 (their tables draw nothing)."""
    out = np.zeros(values.shape[1:] + (4,), np.float32)
    for lane in range(min(len(values), 4)):
        lo, hi = value_range_of(ranges[lane])
        out[..., lane] = (np.asarray(values[lane], dtype=np.float64) - lo) / (hi - lo)
    return out


def value_range_of(given: tuple[float, float]) -> tuple[float, float]:
    """A value range widened as `value_range` widens a single value."""
    lo, hi = float(given[0]), float(given[1])
    if not hi > lo:
        pad = max(abs(lo) * 1e-6, 0.5)
        lo, hi = lo - pad, hi + pad
    return lo, hi


def channel_tables(
    tfs: Sequence[TransferFunction1D], weights: Sequence[float], spans: Sequence[tuple[float, float]], n: int
) -> NDArray[np.float32]:
    """(rows, n, 4), rows a multiple of 4: channel c's colour and weighted extinction w_c tau_c per world
    unit over its own range (Max 1995: the channels' densities add); zero rows pad the last texture."""
    rows = max(4, -(-len(tfs) // 4) * 4)
    out = np.zeros((rows, n, 4), np.float32)
    for c, (tf, w, (lo, hi)) in enumerate(zip(tfs, weights, spans, strict=True)):
        row = post_tf_table(tf, lo, hi, n)[0]
        row[:, 3] *= np.float32(w)
        out[c] = row
    return out
