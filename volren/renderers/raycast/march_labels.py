"""A label volume's sample in numba: the shared kernel `volren.kernels.label_sample` (a transfer
function per label, blended across label boundaries, Real-Time Volume Graphics section 16.5),
named here for raycast's readers. The march around it is `march_mixed`'s.
"""

from __future__ import annotations

from volren.kernels.label_sample import label_sample
from volren.kernels.mixed_inputs import LabelClassification

__all__ = ["LabelClassification", "label_sample"]
