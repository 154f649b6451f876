"""The rule of a renderer's `image_stride` option (adaptive image refinement, `image_refinement`).

Why a module of its own: a renderer declares its options when it is imported, and the rule must
not import the refinement's numba kernels with it.
"""

from __future__ import annotations

from volren.model.option_rule import OptionRule


def is_stride(stride: object) -> bool:
    """Whether `stride` is a power of two from 1 to 64 (an int, not a bool): the block sizes the
    refinement halves down to single pixels."""
    return (
        not isinstance(stride, bool)
        and isinstance(stride, int)
        and 1 <= stride <= 64
        and not stride & (stride - 1)
    )


#: The rule of a renderer's image_stride option (its OptionSpec).
STRIDE_RULE = OptionRule(is_stride, "1, 2, 4, 8, 16, 32 or 64")
