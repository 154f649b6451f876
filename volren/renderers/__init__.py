"""Renderers: the contract (`base`), discovery (`registry`) and one subpackage per renderer.

Renderers receive `volren.model` objects only; they never import Qt or read files.
"""

from volren.renderers.base import Capabilities, FrameStats, KindSupport, Renderer, RendererBase
from volren.renderers.registry import RendererRegistry, registry

__all__ = [
    "Capabilities",
    "FrameStats",
    "KindSupport",
    "Renderer",
    "RendererBase",
    "RendererRegistry",
    "registry",
]
