"""benchmarks.golden_images: a saved set compared to the bit, refusals included."""

from __future__ import annotations

import numpy as np

from benchmarks.golden_images import differences


def test_equal_sets_have_no_differences_and_one_changed_bit_is_found():
    image = np.zeros((4, 5, 4), np.float32)
    saved = {"a/q=draft": image, "b/mip": np.frombuffer(b"no meshes", np.uint8)}
    assert differences(saved, {k: v.copy() for k, v in saved.items()}) == []
    changed = image.copy()
    changed[2, 3, 1] = np.nextafter(np.float32(0), np.float32(1))
    assert differences(saved, {**saved, "a/q=draft": changed}) == ["a/q=draft: max |diff| 1.4e-45"]


def test_a_changed_refusal_or_a_missing_image_is_a_difference():
    saved = {"a": np.frombuffer(b"no meshes", np.uint8), "b": np.zeros((2, 2, 4), np.float32)}
    drawn = {"a": np.frombuffer(b"no meshes!", np.uint8)}
    assert differences(saved, drawn) == ["a: missing, or its shape or refusal changed",
                                         "b: missing, or its shape or refusal changed"]  # fmt: skip
