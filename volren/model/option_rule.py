"""A rule a renderer option's value must pass beyond its kind and range: data, so that the kernels
that define such a rule (`kernels.image_refinement`'s stride) need not import the renderer
contract that declares options with it (`renderers.base.OptionSpec`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class OptionRule:
    """A rule beyond an option's kind and range (a power of two, "0 or at least 16"), and the words
    that say which values pass it, for error messages and help."""

    test: Callable[[Any], bool]
    allowed: str
