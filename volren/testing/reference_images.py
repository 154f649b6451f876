"""Reference images cached on disk by a hash of everything that determines them.

The reference renderer is slow by design; comparisons and benchmarks ask for the same frames
again and again, so its images are kept under ``~/.cache/volren/reference`` (or
$VOLREN_REFERENCE_CACHE) as .npy files named by the SHA-256 of the volume's contents, the TF,
the camera, the size and the settings.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from volren.api import prepared_renderer
from volren.model.camera import Camera
from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.settings import RenderSettings
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import TetVolume, UniformVolume, Volume
from volren.renderers.base import ProgressCallback

#: Bump when the reference renderer's results change, so stale images are not reused.
REFERENCE_VERSION = 2


def cache_folder() -> Path:
    default = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "volren" / "reference"
    return Path(os.environ.get("VOLREN_REFERENCE_CACHE", default))


def volume_digest(volume: Volume) -> str:
    h = hashlib.sha256()
    if isinstance(volume, UniformVolume):
        h.update(
            json.dumps(
                [volume.spacing, volume.origin, volume.values.shape, str(volume.values.dtype)]
            ).encode()
        )
        h.update(np.ascontiguousarray(volume.values).tobytes())
        # a label map changes the image of a label TF; volumes without one keep their keys
        if volume.labels is not None:
            h.update(f"labels {volume.labels.values.dtype} {volume.labels.values.shape}".encode())
            h.update(np.ascontiguousarray(volume.labels.values).tobytes())
        # so do the channels for a channel TF; volumes without them keep their keys as well
        if volume.channels is not None:
            h.update(f"channels {volume.channels.values.dtype} {volume.channels.values.shape}".encode())
            h.update(np.ascontiguousarray(volume.channels.values).tobytes())
    else:
        assert isinstance(volume, TetVolume)
        for array in (volume.points, volume.tets, volume.values):
            h.update(str(array.dtype).encode())
            h.update(np.ascontiguousarray(array).tobytes())
    return h.hexdigest()


def reference_settings(settings: RenderSettings) -> RenderSettings:
    """The settings that matter to the converged reference: appearance and the clip region, not
    sampling or tables."""
    return RenderSettings(
        shade=settings.shade,
        ambient=settings.ambient,
        diffuse=settings.diffuse,
        specular=settings.specular,
        specular_power=settings.specular_power,
        blend_mode=settings.blend_mode,
        clip=settings.clip,
    )


def scene_key(
    volume: Volume,
    tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction,
    camera: Camera,
    width: int,
    height: int,
    settings: RenderSettings,
) -> str:
    payload = {
        "reference_version": REFERENCE_VERSION,
        "volume": volume_digest(volume),
        "tf": tf.to_dict(),
        "camera": camera.to_dict(),
        "size": [width, height],
        "settings": settings.to_dict(),
    }
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


def reference_image(
    volume: Volume,
    tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction,
    camera: Camera,
    width: int,
    height: int,
    settings: RenderSettings | None = None,
    progress: ProgressCallback | None = None,
    folder: Path | None = None,
) -> NDArray[np.float32]:
    """The `reference` renderer's image of this scene, from the cache when it was rendered before."""
    settings = reference_settings(settings or RenderSettings())
    folder = folder or cache_folder()
    path = folder / f"{scene_key(volume, tf, camera, width, height, settings)}.npy"
    if path.exists():
        return np.load(path)
    with prepared_renderer("reference", volume, tf, settings) as renderer:
        image = renderer.render(camera, width, height, progress)
    folder.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.npy")
    np.save(tmp, image)
    tmp.replace(path)
    return image
