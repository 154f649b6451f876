"""A renderer made and fed with a volume, a TF and settings, released when done.

Why here: preparing (a renderer's textures, bricks, octrees, tables for this volume and TF) is the
costly part of a first frame, so every path to pixels prepares through one function, and a
caller drawing many frames keeps what it prepared (`volren.draw.drawing.Drawing`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from volren.model.channels import ChannelTransferFunction
from volren.model.labels import LabelTransferFunction
from volren.model.settings import RenderSettings, check_step
from volren.model.transfer_function_2d import TransferFunction
from volren.model.volume import Volume
from volren.renderers.base import Renderer

#: factory(name) -> a new renderer (the registry's, or the app's own for its tests).
RendererFactory = Callable[[str], Renderer]
#: settings_for(settings, renderer) -> the settings that renderer draws with.
SettingsFor = Callable[[RenderSettings, Renderer], RenderSettings]


@dataclass(frozen=True)
class Preparation:
    """How a renderer is made and fed. By default: from the registry, a step too small for any
    renderer to honour refused (`check_step`), then the volume, TF and settings. The app makes its
    renderers through its own factory and gives each the settings of a still frame for its
    capabilities (`settings_for`), before the volume, as its viewport does."""

    factory: RendererFactory | None = None
    settings_for: SettingsFor | None = None


#: The default: renderers from the registry, the step checked, fed volume, TF, then settings.
FROM_REGISTRY = Preparation()


def _registry_create(name: str) -> Renderer:
    from volren.renderers.registry import registry

    return registry.create(name)


def prepare(name: str, volume: Volume, tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction, settings: RenderSettings | None = None,
            how: Preparation = FROM_REGISTRY) -> Renderer:  # fmt: skip
    """A new renderer `name` holding the volume, TF and settings; the caller releases it."""
    settings = settings or RenderSettings()
    if how.settings_for is None:
        check_step(settings.step, volume.bounds, volume.characteristic_length)
    renderer = (how.factory or _registry_create)(name)
    try:
        if how.settings_for is not None:
            renderer.set_settings(how.settings_for(settings, renderer))
        renderer.set_volume(volume)
        renderer.set_transfer_function(tf)
        if how.settings_for is None:
            renderer.set_settings(settings)
    except BaseException:
        renderer.release()
        raise
    return renderer


@contextmanager
def prepared_renderer(
    name: str, volume: Volume, tf: TransferFunction | LabelTransferFunction | ChannelTransferFunction, settings: RenderSettings | None = None,
    how: Preparation = FROM_REGISTRY,
) -> Iterator[Renderer]:  # fmt: skip
    """``with prepared_renderer(...) as r``: `prepare`, released at the end of the block (the
    Protocol asks for no context-manager methods). A step too small for any renderer to honour is
    refused here, where the bench and the reference images pass as well as `volren.render`."""
    renderer = prepare(name, volume, tf, settings, how)
    try:
        yield renderer
    finally:
        renderer.release()
