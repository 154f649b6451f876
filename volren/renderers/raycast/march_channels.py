"""A multi-channel volume's sample in numba: the shared kernel `volren.kernels.channel_sample` (each
channel's TF at its own trilinear value, extinctions and emissions added, Max 1995), named here for
raycast's readers. The march around it is `march_mixed`'s.
"""

from __future__ import annotations

from volren.kernels.channel_sample import channel_sample
from volren.kernels.mixed_inputs import ChannelClassification

__all__ = ["ChannelClassification", "channel_sample"]
