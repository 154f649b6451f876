"""Movies to files: MP4 (H.264, through the ffmpeg that imageio-ffmpeg's wheel ships) and GIF
(Pillow, through imageio).

MP4 is H.264 in yuv420p at CRF 18 (visually lossless, and what every player and browser plays);
`lossless` makes it RGB H.264 at QP 0, which decodes to exactly the frames given (for comparison
and further editing; fewer players take it). yuv420p needs even sides, so an odd side is padded
by repeating the last row or column. GIF is 256 colours per frame, at the centisecond frame
delays GIF allows; Pillow merges identical consecutive frames into one that lasts as long.

The movie is written beside the target and renamed over it when complete, so a failed or
cancelled movie leaves no half-written file and an old movie of that name intact.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import ExitStack, contextmanager, suppress
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from PIL import Image

from volren.errors import VolrenError, file_error
from volren.io.safe_write import atomic_target, check_output
from volren.model.animation import check_fps

#: The movie formats, by file suffix.
MOVIE_SUFFIXES = (".mp4", ".gif")
#: H.264's constant rate factor for the default MP4: 18 is "visually lossless".
MP4_CRF = 18
INSTALL_HINT = "pip install 'volren[movie]'"
#: The most frames a second a GIF plays at: its frames last whole hundredths of a second, Pillow
#: writes a shorter frame as 0, and browsers show a frame of 0 or 1 hundredths for 10 of them.
GIF_MAX_FPS = 50.0


def check_movie_path(path: str | Path, flag: str | None = None) -> Path:
    """The movie's path, or a one-line error (naming `flag` where given): a known suffix, a file
    that can be written (`check_output`), its encoder installed (checked before anything is
    rendered)."""
    path = Path(path)
    if path.suffix.lower() not in MOVIE_SUFFIXES:
        raise VolrenError(f"{path}: a movie is written as {' or '.join(MOVIE_SUFFIXES)} (by its suffix), "
                          f"not {path.suffix or 'a file without a suffix'}")  # fmt: skip
    check_output(path, flag)
    _imageio()
    if path.suffix.lower() == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401 - the encoder itself
        except ImportError:
            raise VolrenError(f"{path}: MP4 movies need imageio-ffmpeg, which is not installed: "
                              f"{INSTALL_HINT}") from None  # fmt: skip
    return path


def check_movie_fps(path: str | Path, fps: float) -> float:
    """`fps`, or a one-line error naming `path` where its format cannot play that many frames a
    second (`check_fps`'s range, and at most GIF_MAX_FPS for a GIF)."""
    fps = check_fps(fps)
    if Path(path).suffix.lower() == ".gif" and fps > GIF_MAX_FPS:
        raise VolrenError(f"{path}: a GIF plays at most {GIF_MAX_FPS:g} frames a second (its frames last whole "
                          f"hundredths of a second, 2 at least in browsers); for {fps:g} fps write an MP4")  # fmt: skip
    return fps


def _imageio() -> Any:
    try:
        import imageio.v2 as imageio
    except ImportError:
        raise VolrenError(f"movies need imageio, which is not installed: {INSTALL_HINT}") from None
    return imageio


def _even(frame: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """yuv420p halves the chroma resolution: pad an odd side with its last row or column."""
    pad = ((0, frame.shape[0] % 2), (0, frame.shape[1] % 2), (0, 0))
    return np.pad(frame, pad, mode="edge") if any(p[1] for p in pad) else frame


class MovieWriter:
    """Appends 8-bit RGB frames, all of one size, to an open movie file (see `movie_writer`)."""

    def __init__(self, path: Path, tmp: Path, fps: float, lossless: bool) -> None:
        self.path, self.fps, self.lossless = path, check_movie_fps(path, fps), lossless
        self.frames = 0
        self._tmp = tmp
        self._shape: tuple[int, ...] | None = None
        self._writer = self._open(_imageio(), tmp)

    def _open(self, imageio: Any, tmp: Path) -> Any:
        if self.path.suffix.lower() == ".gif":
            return imageio.get_writer(tmp, format="GIF", mode="I", duration=1000.0 / self.fps, loop=0)
        if self.lossless:
            codec, pixels, params = "libx264rgb", "rgb24", ["-qp", "0"]
        else:
            codec, pixels, params = "libx264", "yuv420p", ["-crf", str(MP4_CRF)]
        return imageio.get_writer(tmp, format="FFMPEG", mode="I", fps=self.fps, codec=codec, quality=None,
                                  pixelformat=pixels, macro_block_size=1, output_params=params,
                                  ffmpeg_log_level="error")  # fmt: skip

    def append(self, frame: NDArray[np.uint8]) -> None:
        """Add one (H, W, 3) uint8 frame; every frame must have the first one's size."""
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3:
            raise VolrenError(
                f"{self.path}: a movie frame must be (H, W, 3) uint8, got {frame.shape} {frame.dtype}"
            )
        if self._shape is not None and frame.shape != self._shape:
            raise VolrenError(f"{self.path}: frame {self.frames} is {frame.shape[1]}x{frame.shape[0]}, the movie "
                              f"{self._shape[1]}x{self._shape[0]}")  # fmt: skip
        self._shape = frame.shape
        if self.path.suffix.lower() == ".mp4" and not self.lossless:
            frame = _even(frame)
        try:
            self._writer.append_data(np.ascontiguousarray(frame))
        except (OSError, RuntimeError, ValueError) as exc:
            raise file_error(self.path, f"cannot write the movie: {_one_line(exc)}") from None
        self.frames += 1

    def close(self) -> None:
        """Finish the file, and check that it holds the frames given: ffmpeg can fail with no
        error for the caller (a 0-byte file, a movie with no video)."""
        try:
            self._writer.close()
        except (OSError, RuntimeError, ValueError, OverflowError) as exc:  # a GIF frame over 655 s
            raise file_error(self.path, f"cannot finish the movie: {_one_line(exc)}") from None
        written = self._frames_written()
        if not (
            written == self.frames or (self.path.suffix.lower() == ".gif" and 1 <= written <= self.frames)
        ):
            raise file_error(self.path, f"cannot finish the movie: the encoder wrote {written} of its "
                                        f"{self.frames} frames")  # fmt: skip

    def _frames_written(self) -> int:
        """The frames in the finished file (a GIF merges identical consecutive ones); 0 where it
        cannot be read."""
        try:
            if self.path.suffix.lower() == ".gif":
                with Image.open(self._tmp) as image:
                    return int(getattr(image, "n_frames", 1))
            import imageio_ffmpeg

            return int(imageio_ffmpeg.count_frames_and_secs(str(self._tmp))[0])
        except (OSError, RuntimeError, ValueError):
            return 0


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())[:300]


@contextmanager
def movie_writer(path: str | Path, fps: float, lossless: bool = False) -> Iterator[MovieWriter]:
    """An open movie at `path` (MP4 or GIF, by suffix) at `fps`; complete when the block ends
    normally, and not there at all (an older file of that name kept) when it raises."""
    path = check_movie_path(path)
    with ExitStack() as stack:
        try:
            tmp = stack.enter_context(atomic_target(path))
        except OSError as exc:  # the folder takes no new file
            raise file_error(path, f"cannot write the movie: {exc.strerror}") from None
        writer = MovieWriter(path, tmp, fps, lossless)
        try:
            yield writer
            if writer.frames == 0:
                raise VolrenError(f"{path}: a movie needs at least one frame")
        except BaseException:
            with suppress(VolrenError):  # the block's error is the one to report
                writer.close()
            raise
        writer.close()
