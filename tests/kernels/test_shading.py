"""The shared Blinn-Phong kernel against DESIGN.md's closed form, and the no-shading threshold."""

from __future__ import annotations

import math

import numpy as np
import pytest

from volren.kernels.shading import (
    GRADIENT_EPS,
    ShadeParams,
    blinn_phong_factors,
    gradient_threshold,
    headlight_half_vector,
    shade,
)

KA, KD, KS, POWER = 0.1, 0.7, 0.2, 10.0


def factors(g, light, half, gthr=0.0):
    return blinn_phong_factors(*g, *half, ShadeParams(True, KA, KD, KS, POWER, gthr, *light))


def closed_form(g, light, view):
    """DESIGN.md's formula in numpy: N = -g/|g| turned toward L, H = normalize(L + V)."""
    g, light, view = (np.asarray(v, dtype=np.float64) for v in (g, light, view))
    n = -g / np.linalg.norm(g)
    if n @ light < 0.0:
        n = -n
    h = (light + view) / np.linalg.norm(light + view)
    return KA + KD * (n @ light), KS * max(n @ h, 0.0) ** POWER


def test_a_parallel_headlight_on_an_exact_normal():
    """g = -(0, 3, 4): N = (0, 0.6, 0.8), and with L = V = z, H = L and N.L = N.H = 0.8."""
    diffuse, specular = factors((0.0, -3.0, -4.0), (0.0, 0.0, 1.0), (0.0, 0.0, 1.0))
    assert diffuse == KA + KD * 0.8
    assert specular == KS * 0.8**POWER


@pytest.mark.parametrize("g", [(0.3, -1.2, 0.5), (-2.0, 0.1, -0.4), (1e-3, 2e-3, -5e-4)])
def test_factors_match_the_closed_form_under_perspective(g):
    light = np.array([0.2, -0.3, 0.9]) / np.linalg.norm([0.2, -0.3, 0.9])
    direction = np.array([0.1, 0.4, -0.8]) / np.linalg.norm([0.1, 0.4, -0.8])
    half = headlight_half_vector(*light, *direction)
    np.testing.assert_allclose(factors(g, light, half), closed_form(g, light, -direction), rtol=1e-14)


def test_lighting_is_two_sided():
    light, half = (0.0, 0.6, 0.8), (0.0, 0.0, 1.0)
    assert factors((0.2, 0.5, -1.0), light, half) == factors((-0.2, -0.5, 1.0), light, half)


def test_no_shading_at_or_below_the_threshold_nor_where_the_gradient_is_not_finite():
    light = half = (0.0, 0.0, 1.0)
    assert factors((0.0, 0.0, 0.5), light, half, gthr=0.5) == (1.0, 0.0)
    assert factors((0.0, 0.0, 0.5), light, half, gthr=0.4) != (1.0, 0.0)
    assert factors((0.0, math.nan, 1.0), light, half) == (1.0, 0.0)
    assert factors((0.0, math.inf, 1.0), light, half) == (1.0, 0.0)


def test_shade_clamps_the_lit_colour():
    sp = ShadeParams(True, KA, KD, KS, POWER, 0.0, 0.0, 0.0, 1.0)
    diffuse, specular = factors((0.0, -3.0, -4.0), sp[6:9], (0.0, 0.0, 1.0))
    r, g, b = shade(sp, 0.5, 1.0, 0.0, 0.0, -3.0, -4.0, 0.0, 0.0, 1.0)
    assert (r, g, b) == (0.5 * diffuse + specular, min(diffuse + specular, 1.0), specular)


def test_the_threshold_is_a_fraction_of_the_span_per_length():
    assert gradient_threshold(200.0, 0.5) == GRADIENT_EPS * 200.0 / 0.5
