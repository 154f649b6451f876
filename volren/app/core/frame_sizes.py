"""Sizes of the frames the app asks for (no Qt).

Frames become displayable pixels through `volren.io.image_io.to_png_pixels`, the same conversion
screenshots use: rgb + (1 - a) * background, no gamma (VTK and ParaView show their framebuffer
values as they are, and the app should look like them).
"""

from __future__ import annotations


def preview_size(width: int, height: int, scale: float) -> tuple[int, int]:
    """The size of a reduced-cost frame: each side times `scale` (0.5 renders a quarter of the pixels)."""
    return max(1, round(width * scale)), max(1, round(height * scale))


def adaptive_preview_scale(
    ms_per_pixel: float | None,
    full_pixels: int,
    budget_ms: float = 50.0,
    max_scale: float = 0.5,
    min_scale: float = 0.1,
    fixed_ms: float = 0.0,
) -> float:
    """The side scale of preview frames that keeps one within `budget_ms`.

    A frame is taken to cost `fixed_ms` plus `ms_per_pixel` per pixel (`FrameCost` fits both from
    the renderer's frames of two sizes). Fast renderers get `max_scale` (a quarter of the pixels);
    slow ones (the exact reference renderer takes seconds per full frame) get coarser previews,
    down to `min_scale`, so dragging still answers. Where the fixed part alone exceeds the budget
    (a software-GL slicer's passes, shear-warp's compositing at the volume's resolution), fewer
    pixels would only blur the preview without making it faster: it gets `max_scale`. (Assuming
    cost proportional to pixels kept such renderers at the floor, 1 % of the pixels.)
    """
    if not ms_per_pixel or ms_per_pixel <= 0 or full_pixels <= 0:
        return max_scale
    if fixed_ms >= budget_ms:
        return max_scale
    scale = ((budget_ms - fixed_ms) / (ms_per_pixel * full_pixels)) ** 0.5
    return float(min(max_scale, max(min_scale, scale)))


#: Frames remembered per size; the fastest of them stands for the size. Why the fastest: a frame
#: right after a TF edit also pays the renderer's reclassification, which previews of a rotation
#: do not, and one such frame taken as the full size's cost made the previews 2 % of the pixels.
FRAMES_PER_SIZE = 5
#: How far above the latest previews' time the model may predict it before the largest size's
#: times are taken as stale (`FrameCost._full_is_stale`). At 2, shear-warp's first frames along a
#: new axis (505 and 411 ms at a quarter of bonsai's 947x896 view), through which the line
#: predicted 1.7x what the previews then took, kept the rotation's previews at 5 % of the pixels.
STALE_FACTOR = 1.25


class FrameCost:
    """A renderer's frame time as fixed + per-pixel cost, fitted through its full frames and its
    latest preview size. Why those two: consecutive previews differ little in size (each is sized
    from the last estimate), and a line through two nearly equal sizes is mostly noise; and the
    latest previews only, because earlier ones may have paid for something else (a TF drag's
    previews each rebuild the renderer's tables; a rotation's do not)."""

    def __init__(self) -> None:
        self._full: tuple[int, list[float]] | None = None  # the largest size drawn, its recent ms
        self._preview: tuple[int, list[float]] | None = None  # the latest smaller size, its ms

    def note(self, pixels: int, ms: float) -> None:
        if self._full is None or pixels >= self._full[0]:
            times = self._full[1] if self._full is not None and self._full[0] == pixels else []
            self._full = (pixels, (times + [ms])[-FRAMES_PER_SIZE:])
        else:
            times = self._preview[1] if self._preview is not None and self._preview[0] == pixels else []
            self._preview = (pixels, (times + [ms])[-FRAMES_PER_SIZE:])
            if self._full_is_stale():
                self._full, self._preview = self._preview, None

    def _full_is_stale(self) -> bool:
        """Whether the largest size's times make the model predict more than `STALE_FACTOR` times
        what the latest preview size takes. A frame's cost grows at most in proportion to its pixels
        (its fixed part does not grow), so a line through both sizes that meets zero pixels below
        zero ms holds times the largest size paid once (a table built for a new TF, shear-warp's
        first frame along an axis), which no newer frame of that size replaces while the previews
        stay smaller: sized from them, bonsai's previews stayed at 8-10 % of the pixels, drawn in
        half their budget or less."""
        model = self.model()
        if model is None or self._preview is None:
            return False
        fixed, per_pixel = model
        pixels, ms = self._preview[0], min(self._preview[1])
        return fixed + per_pixel * pixels > STALE_FACTOR * ms

    def model(self) -> tuple[float, float] | None:
        """(fixed ms, ms per pixel), or None before any frame; all of it per pixel, at the cheaper
        rate of the two sizes, until a preview at most half the full frame's pixels has been drawn.
        Why the cheaper: a size drawn a few times may have paid something once at each (shear-warp's
        first frames along a new axis took 0.7 s; taken as its rate, bonsai's rotation previews
        stayed at 17 % of the pixels, drawn in 50 ms where 80 were allowed)."""
        if self._full is None:
            return None
        p1, t1 = self._full[0], min(self._full[1])
        if self._preview is None or p1 < 2 * self._preview[0]:
            rate = t1 / max(p1, 1)
            if self._preview is not None:
                rate = min(rate, min(self._preview[1]) / max(self._preview[0], 1))
            return 0.0, rate
        p0, t0 = self._preview[0], min(self._preview[1])
        per_pixel = max((t1 - t0) / (p1 - p0), 0.0)
        fixed = max(t1 - per_pixel * p1, 0.0)
        if per_pixel == 0.0:  # no growth with size measured: call it all fixed, with a floor per pixel
            per_pixel = 1e-9
        return fixed, per_pixel
