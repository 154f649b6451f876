"""Which renderers can draw what is loaded, and what to use instead (no Qt).

The chooser lists every registered renderer so people see what exists; the ones that cannot draw
the loaded volume (or failed to import) are disabled with the reason. The app never leaves a
volume without a usable renderer: `pick_renderer` keeps the current one when it can, else takes
the one `auto` measures fastest among those that can (`volren.quality.choose_renderer`), as for
the first volume.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

from volren.model.settings import RenderSettings
from volren.renderers.registry import RendererRegistry
from volren.renderers.registry import registry as default_registry


@dataclass(frozen=True)
class RendererOption:
    """One entry of the chooser: enabled when `reason` is None."""

    name: str
    reason: str | None

    @property
    def enabled(self) -> bool:
        return self.reason is None


def renderer_options(
    volume_kind: str | None,
    settings: RenderSettings | None = None,
    registry: RendererRegistry = default_registry,
    tf_dims: int = 1,
    labels: bool = False,
    channels: bool = False,
) -> tuple[list[RendererOption], list[str]]:
    """Every registered renderer with why it cannot draw `volume_kind` with a `tf_dims`-D TF and
    `settings` (None: it can); with `labels`, drawn by label with a TF per label (RTVG chapter 16),
    at the settings it draws labels with (`volren.quality.label_settings`: no pre-integration
    where it has none for labels); with `channels`, mixing several channels with a TF each (Max
    1995, section 2), without pre-integration (`volren.quality.channel_settings`).

    Also returns the warnings the registry raised while importing renderers (a broken plugin), so
    the app can show them instead of letting them escape; the registry reports each one once.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if volume_kind is None:
            reasons: dict[str, str | None] = {}
            for name in registry.names():
                try:
                    registry.get(name)
                    reasons[name] = None
                except Exception as exc:  # noqa: BLE001 - any import failure disables the entry
                    reasons[name] = str(exc)
        elif labels or channels:
            reasons = _label_reasons(registry, volume_kind, tf_dims, settings, channels=channels)
        else:
            reasons = registry.compatible(volume_kind, tf_dims, settings)
    options = [RendererOption(name, reasons.get(name)) for name in registry.names()]
    return options, [str(w.message) for w in caught]


def _label_reasons(registry: RendererRegistry, kind: str, tf_dims: int,
                   settings: RenderSettings | None, channels: bool = False) -> dict[str, str | None]:  # fmt: skip
    """Why each renderer cannot draw labels (or, with `channels`, mix channels) at the settings it
    draws them with."""
    from volren.quality import channel_settings, label_settings

    adjust = channel_settings if channels else label_settings

    reasons: dict[str, str | None] = {}
    for name in registry.names():
        try:
            caps = registry.capabilities(name)
        except Exception as exc:  # noqa: BLE001 - any import failure disables the entry
            reasons[name] = str(exc)
            continue
        drawn = adjust(caps, kind, settings) if settings is not None else None
        reasons[name] = caps.unsupported_reason(kind, tf_dims, drawn, labels=not channels, channels=channels)
    return reasons


def pick_renderer(options: list[RendererOption], current: str | None,
                  measured: Callable[[list[str]], str | None] | None = None) -> str | None:  # fmt: skip
    """`current` when it is usable, else the one `measured` picks among the usable ones (auto's
    measured choice), else the first usable one, else None."""
    usable = [o.name for o in options if o.enabled]
    if current in usable:
        return current
    chosen = measured(usable) if measured is not None and usable else None
    if chosen in usable:
        return chosen
    return usable[0] if usable else None
