"""The final 2D warp against a float64 numpy oracle: every output pixel's ray point, Catmull-Rom or
bilinear taps (those outside the intermediate image dropped), then the output rules."""

from __future__ import annotations

import numpy as np
import pytest
from volren_shearwarp.warp import warp


def _weights(f: np.ndarray, cubic: bool) -> list[np.ndarray]:
    if not cubic:
        return [np.zeros_like(f), 1.0 - f, f, np.zeros_like(f)]
    return [-0.5 * f**3 + f**2 - 0.5 * f, 1.5 * f**3 - 2.5 * f**2 + 1.0, -1.5 * f**3 + 2.0 * f**2 + 0.5 * f,
            0.5 * f**3 - 0.5 * f**2]  # fmt: skip


def oracle(inter: np.ndarray, hom: np.ndarray, sign: float, a0: float, b0: float, scale: float, width: int,
           height: int, cubic: bool) -> np.ndarray:  # fmt: skip
    """The warp, pixel by pixel in float64."""
    ih, iw = inter.shape[:2]
    x = (np.arange(width) + 0.5) / width * 2.0 - 1.0
    y = 1.0 - (np.arange(height) + 0.5) / height * 2.0
    x, y = np.meshgrid(x, y)
    hw = hom[2, 0] * x + hom[2, 1] * y + hom[2, 2]
    with np.errstate(divide="ignore", invalid="ignore"):  # behind the plane's horizon: not seen
        p = ((hom[0, 0] * x + hom[0, 1] * y + hom[0, 2]) / hw - a0) * scale
        q = ((hom[1, 0] * x + hom[1, 1] * y + hom[1, 2]) / hw - b0) * scale
    seen = (hw * sign > 0) & (p > -2.0) & (p < iw + 1.0) & (q > -2.0) & (q < ih + 1.0)
    p, q = np.where(seen, p, 0.0), np.where(seen, q, 0.0)
    p0, q0 = np.floor(p).astype(int), np.floor(q).astype(int)
    wp, wq = _weights(p - p0, cubic), _weights(q - q0, cubic)
    out = np.zeros((height, width, 4))
    for dq in range(4):
        for dp in range(4):
            pp, qq = p0 + dp - 1, q0 + dq - 1
            inside = seen & (pp >= 0) & (pp < iw) & (qq >= 0) & (qq < ih)
            taps = inter[np.clip(qq, 0, ih - 1), np.clip(pp, 0, iw - 1)].astype(np.float64)
            out += np.where(inside, wq[dq] * wp[dp], 0.0)[..., None] * taps
    alpha = np.clip(out[..., 3:], 0.0, 1.0)
    return np.concatenate([np.minimum(np.maximum(out[..., :3], 0.0), alpha), alpha], axis=-1)


@pytest.mark.parametrize("cubic", [True, False])
@pytest.mark.parametrize("projective", [False, True, "horizon"])
@pytest.mark.parametrize("pattern", ["dense", "sparse", "cluster"])
def test_the_warp_is_the_oracle_inside_and_at_the_edges(
    cubic: bool, projective: bool | str, pattern: str
) -> None:
    """Also on a sparse image (3 % of its pixels drawn, the rest transparent black), where the warp
    skips the pixels whose taps are all empty (`empty_taps`): a tap window one pixel too small
    would lose the lone pixels' footprints; on one small drawn patch, whose rim's pixels must keep
    their taps; and with the plane's horizon inside the frame (pixels whose w has the wrong sign
    see nothing)."""
    rng = np.random.default_rng(7)
    inter = rng.random((37, 53, 4)).astype(np.float32)
    inter[..., :3] *= inter[..., 3:]
    if pattern == "sparse":
        inter[rng.random((37, 53)) >= 0.03] = 0.0
    elif pattern == "cluster":
        patch = inter[17:20, 24:27].copy()
        inter[:] = 0.0
        inter[17:20, 24:27] = patch
    turn = 0.4
    hom = np.array([[30 * np.cos(turn), -30 * np.sin(turn), 25.0], [30 * np.sin(turn), 30 * np.cos(turn), 18.0],
                    [0.0, 0.0, 1.0]])  # fmt: skip
    if projective == "horizon":
        hom[2] = (0.2, 1.0, 0.8)  # w <= 0 over the bottom rows of the frame
    elif projective:
        hom[2, :2] = (0.15, -0.1)
    got = warp(inter, hom, 1.0, (-1.5, 0.5), 1.1, 96, 80, cubic)
    want = oracle(inter, hom, 1.0, -1.5, 0.5, 1.1, 96, 80, cubic)
    seen = want[..., 3] > 0
    if pattern == "dense":
        assert seen.mean() > 0.3 and (~seen).any()  # the image's edges fall inside the frame
    else:
        assert 0.0 < seen.mean() < 0.2  # footprints of lone pixels or of the patch, most of the frame empty
    assert got.dtype == np.float32
    np.testing.assert_allclose(got, want, atol=2e-6)
