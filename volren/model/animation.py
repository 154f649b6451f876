"""A movie's timeline: how many frames, how fast, and the camera and TF of each frame.

Without camera keyframes the camera orbits the scene's camera about its view-up axis (an orbit
view's azimuth grows), so frame i is exactly `volren render --azimuth A0 + i * degrees / frames`.
A whole number of turns leaves out the last frame, which would repeat the first: the movie loops.

Keyframes sit at normalized times in [0, 1] (frame i is at i / (frames - 1)), as in ParaView's
animation view: the same keyframes make a longer or a shorter movie. Between two keyframes the
camera and TF are interpolated linearly: orbit views in azimuth, elevation and log zoom; explicit
cameras in focal point, distance, the directions (slerp), view angle and parallel scale; TFs as
in `volren.model.tf_blend`. Before the first keyframe and after the last, the nearest one holds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from volren.errors import VolrenError
from volren.model.camera import Camera
from volren.model.clip_region import ClipRegion, blend_clip_regions
from volren.model.scene import OrbitView, camera_from_dict
from volren.model.settings import is_finite
from volren.model.tf_blend import blend_transfer_functions
from volren.model.transfer_function_2d import TransferFunction, transfer_function_from_dict

#: More frames than this is a typo (at 60 fps, 28 minutes), not a movie.
MAX_FRAMES = 100_000
MAX_FPS = 240.0
#: Fewer frames a second than this is a typo (a frame every 100 s), and what ffmpeg (a 0-byte
#: file below about 1e-6) and GIF (at most 655 s a frame) cannot write.
MIN_FPS = 0.01
DEFAULT_FRAMES = 120
DEFAULT_FPS = 30.0

View = OrbitView | Camera


@dataclass(frozen=True)
class CameraKey:
    time: float
    view: View


@dataclass(frozen=True)
class TFKey:
    time: float
    transfer_function: TransferFunction


@dataclass(frozen=True)
class ClipKey:
    time: float
    clip: ClipRegion


def check_frames(frames: Any, what: str = "frames") -> int:
    if isinstance(frames, bool) or not isinstance(frames, int | np.integer) or not 1 <= frames <= MAX_FRAMES:
        raise VolrenError(f"{what} must be a whole number from 1 to {MAX_FRAMES:,}, got {frames!r:.40}")
    return int(frames)


def check_fps(fps: Any, what: str = "fps") -> float:
    if isinstance(fps, bool) or not isinstance(fps, int | float) or not (MIN_FPS <= fps <= MAX_FPS):
        raise VolrenError(f"{what} must be a number from {MIN_FPS:g} to {MAX_FPS:g}, got {fps!r:.40}")
    return float(fps)


def _check_time(value: Any, what: str = "'time'") -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0 <= value <= 1:
        raise VolrenError(f"{what} must be a number in [0, 1] (a fraction of the movie), got {value!r:.40}")
    return float(value)


def _segment(times: Sequence[float], t: float) -> tuple[int, int, float]:
    """The keyframes around time `t` and the weight of the second: (i, j, w)."""
    j = int(np.searchsorted(times, t, side="right"))
    if j == 0:
        return 0, 0, 0.0
    if j == len(times):
        return j - 1, j - 1, 0.0
    i = j - 1
    return i, j, (t - times[i]) / (times[j] - times[i])


def _slerp(a: NDArray, b: NDArray, weight: float) -> NDArray:
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    angle = math.acos(float(np.clip(a @ b, -1.0, 1.0)))
    if angle < 1e-9:
        return a
    return (math.sin((1 - weight) * angle) * a + math.sin(weight * angle) * b) / math.sin(angle)


def blend_views(a: View, b: View, weight: float) -> View:
    """The view a fraction `weight` of the way from `a` to `b` (both orbit views, or both cameras)."""
    if weight <= 0:
        return a
    if weight >= 1:
        return b
    if isinstance(a, OrbitView) and isinstance(b, OrbitView):
        return OrbitView(
            azimuth=(1 - weight) * a.azimuth + weight * b.azimuth,
            elevation=(1 - weight) * a.elevation + weight * b.elevation,
            zoom=math.exp((1 - weight) * math.log(a.zoom) + weight * math.log(b.zoom)),
            parallel=a.parallel,
        )
    if isinstance(a, Camera) and isinstance(b, Camera):
        focal = (1 - weight) * np.asarray(a.focal_point) + weight * np.asarray(b.focal_point)
        distance = (1 - weight) * a.distance + weight * b.distance
        back = _slerp(-a.direction, -b.direction, weight)
        up = _slerp(np.asarray(a.view_up, float), np.asarray(b.view_up, float), weight)
        return replace(
            a,
            position=tuple(focal + distance * back),
            focal_point=tuple(focal),
            view_up=tuple(up),
            view_angle=(1 - weight) * a.view_angle + weight * b.view_angle,
            parallel_scale=(1 - weight) * a.parallel_scale + weight * b.parallel_scale,
        ).orthogonalize_view_up()
    raise VolrenError(
        "camera keyframes must all be orbit views (azimuth, elevation, zoom) or all explicit cameras"
    )


@dataclass(frozen=True)
class Animation:
    """The movie's frames: `frames` at `fps`, an orbit of `orbit_degrees` unless camera keyframes
    say otherwise, and TF keyframes (none: the scene's TF throughout)."""

    frames: int = DEFAULT_FRAMES
    fps: float = DEFAULT_FPS
    orbit_degrees: float = 360.0
    camera_keys: tuple[CameraKey, ...] = ()
    tf_keys: tuple[TFKey, ...] = ()
    #: the clip region (planes and box) through the movie: none, the scene's settings' throughout
    clip_keys: tuple[ClipKey, ...] = ()

    def __post_init__(self) -> None:
        check_frames(self.frames)
        check_fps(self.fps)
        _orbit(self.orbit_degrees, "orbit_degrees")
        keys: tuple[CameraKey | TFKey | ClipKey, ...] = (*self.camera_keys, *self.tf_keys, *self.clip_keys)
        for key in keys:
            _check_time(key.time, "keyframe time")
        views = {isinstance(key.view, OrbitView) for key in self.camera_keys}
        if len(views) > 1:
            raise VolrenError("camera keyframes must all be orbit views (azimuth, elevation, zoom) or all explicit "
                              "cameras")  # fmt: skip
        if len({key.view.parallel for key in self.camera_keys}) > 1:
            raise VolrenError("camera keyframes must all be parallel or all perspective projections")
        dims = {key.transfer_function.dims for key in self.tf_keys}
        if len(dims) > 1:
            raise VolrenError("TF keyframes must all be 1D or all 2D transfer functions")
        object.__setattr__(self, "camera_keys", tuple(sorted(self.camera_keys, key=lambda k: k.time)))
        object.__setattr__(self, "tf_keys", tuple(sorted(self.tf_keys, key=lambda k: k.time)))
        object.__setattr__(self, "clip_keys", tuple(sorted(self.clip_keys, key=lambda k: k.time)))
        if len({len(key.clip.planes) for key in self.clip_keys}) > 1:
            raise VolrenError("clip keyframes must all hold the same number of planes")

    @property
    def seconds(self) -> float:
        return self.frames / self.fps

    @property
    def loops(self) -> bool:
        """An orbit of whole turns: the frame after the last would be the first."""
        return not self.camera_keys and self.orbit_degrees != 0 and self.orbit_degrees % 360 == 0

    def time(self, index: int) -> float:
        """Frame `index`'s place in the movie, 0 (first frame) to 1 (last)."""
        return index / (self.frames - 1) if self.frames > 1 else 0.0

    def orbit_angle(self, index: int) -> float:
        """Degrees of azimuth added to the start view at frame `index` (no camera keyframes)."""
        steps = self.frames if self.loops else max(self.frames - 1, 1)
        return self.orbit_degrees * index / steps

    def view(self, index: int, start: View) -> View:
        """Frame `index`'s view; `start` is the scene's camera (where an orbit starts)."""
        if self.camera_keys:
            times = [key.time for key in self.camera_keys]
            i, j, weight = _segment(times, self.time(index))
            return blend_views(self.camera_keys[i].view, self.camera_keys[j].view, weight)
        angle = self.orbit_angle(index)
        if isinstance(start, OrbitView):
            return replace(start, azimuth=start.azimuth + angle)
        return start.azimuth(angle)

    def camera(self, index: int, start: View, bounds: Sequence[float], aspect: float) -> Camera:
        """Frame `index`'s camera, as `volren render` makes it from the same view (an explicit camera
        with its clipping range reset on `bounds`)."""
        view = self.view(index, start)
        if isinstance(view, OrbitView):
            return view.camera(bounds, aspect)
        return view.reset_clipping_range(bounds)  # a moved camera must still see all of the data

    def transfer_function(self, index: int, start: TransferFunction) -> TransferFunction:
        """Frame `index`'s TF; `start` (the scene's) when there are no TF keyframes."""
        if not self.tf_keys:
            return start
        times = [key.time for key in self.tf_keys]
        i, j, weight = _segment(times, self.time(index))
        if weight == 0:  # the keyframe's own TF: frames that hold it share it, and the renderer's tables
            return self.tf_keys[i].transfer_function
        return blend_transfer_functions(
            self.tf_keys[i].transfer_function, self.tf_keys[j].transfer_function, weight
        )

    def clip(self, index: int, start: ClipRegion) -> ClipRegion:
        """Frame `index`'s clip region; `start` (the scene's) when there are no clip keyframes."""
        if not self.clip_keys:
            return start
        times = [key.time for key in self.clip_keys]
        i, j, weight = _segment(times, self.time(index))
        return blend_clip_regions(self.clip_keys[i].clip, self.clip_keys[j].clip, weight)

    def clips_anywhere(self, start: ClipRegion) -> ClipRegion:
        """A region some frame clips to (the first key that clips anything), else `start`: what
        choosing a renderer for the whole movie must allow for."""
        return next((key.clip for key in self.clip_keys if not key.clip.is_empty), start)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Animation:
        """A scene file's "movie" object: frames, fps, orbit (degrees) and keyframes, each with a
        time and a camera and/or an inline transfer_function (`volren.io.load_scene` inlines
        those given by path). Errors start with "movie: "."""
        try:
            return cls._from_dict(data)
        except VolrenError as exc:
            raise VolrenError(f"movie: {exc}") from None

    @classmethod
    def _from_dict(cls, data: Mapping[str, Any]) -> Animation:
        if not isinstance(data, Mapping):
            raise VolrenError(f"must be a JSON object, got {type(data).__name__}")
        unknown = set(data) - {"frames", "fps", "orbit", "keyframes"}
        if unknown:
            raise VolrenError(f"unknown keys {sorted(unknown)}; use frames, fps, orbit, keyframes")
        keyframes = data.get("keyframes", [])
        if not isinstance(keyframes, list):
            raise VolrenError(f"'keyframes' must be a list, got {type(keyframes).__name__}")
        camera_keys, tf_keys, clip_keys = [], [], []
        for index, key in enumerate(keyframes):
            if not isinstance(key, Mapping) or not ({"camera", "transfer_function", "clip"} & set(key)):
                raise VolrenError(f"keyframe {index} must be an object with 'time' and a 'camera', a "
                                  "'transfer_function' and/or a 'clip'")  # fmt: skip
            try:
                extra = set(key) - {"time", "camera", "transfer_function", "clip"}
                if extra:
                    raise VolrenError(f"unknown keys {sorted(extra)}")
                time = _check_time(key.get("time"))
                if "camera" in key:
                    camera_keys.append(CameraKey(time, camera_from_dict(key["camera"])))
                if "transfer_function" in key:
                    tf_keys.append(TFKey(time, transfer_function_from_dict(key["transfer_function"])))
                if "clip" in key:
                    clip_keys.append(ClipKey(time, ClipRegion.from_dict(key["clip"])))
            except VolrenError as exc:
                raise VolrenError(f"keyframe {index}: {exc}") from None
        return cls(
            frames=check_frames(data.get("frames", DEFAULT_FRAMES)),
            fps=check_fps(data.get("fps", DEFAULT_FPS)),
            orbit_degrees=_orbit(data.get("orbit", 360.0)),
            camera_keys=tuple(camera_keys),
            tf_keys=tuple(tf_keys),
            clip_keys=tuple(clip_keys),
        )


def _orbit(value: Any, what: str = "'orbit'") -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not is_finite(value):
        raise VolrenError(f"{what} must be a finite number of degrees, got {value!r:.40}")
    return float(value)
