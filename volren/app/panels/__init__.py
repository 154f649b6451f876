"""Settings panels of the desktop app: each shows part of a `ViewState` and edits it.

Every panel takes the state in its constructor, follows its changes (a loaded scene, undo) without
echoing them back, and changes it only through its setters. The window decides where they go
(docks, tabs); the panels know nothing of each other.
"""

from volren.app.panels.background import BackgroundPanel
from volren.app.panels.base import StatePanel
from volren.app.panels.blend import BlendPanel
from volren.app.panels.channels import ChannelsPanel
from volren.app.panels.clipping import ClippingPanel
from volren.app.panels.crop import CropPanel
from volren.app.panels.dataset_info import DatasetInfoPanel, volume_facts
from volren.app.panels.labels import LabelsPanel
from volren.app.panels.lighting import LightingPanel
from volren.app.panels.sampling import SamplingPanel

__all__ = [
    "BackgroundPanel",
    "BlendPanel",
    "ChannelsPanel",
    "ClippingPanel",
    "CropPanel",
    "DatasetInfoPanel",
    "LabelsPanel",
    "LightingPanel",
    "SamplingPanel",
    "StatePanel",
    "volume_facts",
]
