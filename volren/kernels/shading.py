"""Blinn-Phong shading of a sample, with vtkVolumeProperty's parameters and one headlight.

Why: DESIGN.md's optical model shades the TF colour with a local illumination model when shading
is on; the reference has to pin down exactly which one so that every renderer can match it.

The formulas (all vectors unit length, world space):

    L = -camera.direction                  directional headlight, from the data toward the camera
    V = -ray direction                     toward the eye (L == V for a parallel camera)
    H = normalize(L + V)
    g = grad s                             uniform: central differences at grid points in world
                                           units (one-sided at the borders), interpolated
                                           trilinearly like the scalars; tets: the constant
                                           gradient of the linear field in each tetrahedron
    no shading where |g| <= 1e-6 * (value-range span) / characteristic length
                                           (or g is not finite): the colour stays c
    N = -g / |g|
    if N.L < 0: N = -N                     two-sided lighting (VTK's default)
    c_shaded = clamp(c * (ka + kd * (N.L)) + ks * max(N.H, 0)^p, 0, 1)   per channel

with ka, kd, ks, p = ambient, diffuse, specular, specular_power from RenderSettings. The opacity is
not changed by shading; the shaded colour replaces c in the emission q = c * tau.

`shade_params` gives the per-frame `ShadeParams` (the light L among them) and `half_vector` the
per-ray (H) vector; `shade` applies the formula to one sample.
Every CPU renderer lights through `blinn_phong_factors` (those that pre-integrate colour apply its
two factors to table entries rather than to one colour) and takes its no-shading threshold from
`gradient_threshold`, so that one optical model holds for all of them.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from volren.model.camera import Camera
from volren.model.settings import RenderSettings

#: |grad s| below this fraction of (value-range span / characteristic length) counts as zero.
GRADIENT_EPS = 1e-6


def gradient_threshold(span: float, length: float) -> float:
    """|grad s| at or below which a sample is not shaded, for the value-range span and the
    volume's characteristic length (world units)."""
    return GRADIENT_EPS * float(span) / float(length)


class ShadeParams(NamedTuple):
    """One frame's lighting, passed to the kernels as one bundle (numba types it as a named tuple;
    the field order is the positional order older kernels index)."""

    on: bool
    ambient: float
    diffuse: float
    specular: float
    power: float
    gradient_threshold: float
    lx: float
    ly: float
    lz: float


def shade_params(settings: RenderSettings, camera: Camera, span: float, length: float) -> ShadeParams:
    """The frame's `ShadeParams`: the headlight L = -camera.direction and the no-shading threshold
    for the value-range span and characteristic length."""
    light = -np.asarray(camera.direction, dtype=np.float64)
    gthr = gradient_threshold(span, length)
    return ShadeParams(
        bool(settings.shade),
        float(settings.ambient),
        float(settings.diffuse),
        float(settings.specular),
        float(settings.specular_power),
        gthr,
        float(light[0]),
        float(light[1]),
        float(light[2]),
    )


@njit(nogil=True, cache=True, inline="always")
def headlight_half_vector(lx, ly, lz, dx, dy, dz):
    """H = normalize(L + V) with V = -d for a ray of unit direction d."""
    hx = lx - dx
    hy = ly - dy
    hz = lz - dz
    n = math.sqrt(hx * hx + hy * hy + hz * hz)
    if n > 0.0:
        return hx / n, hy / n, hz / n
    return 0.0, 0.0, 0.0


@njit(nogil=True, cache=True)
def half_vector(sp, dx, dy, dz):
    """`headlight_half_vector` with the light of the tuple `sp`."""
    return headlight_half_vector(sp.lx, sp.ly, sp.lz, dx, dy, dz)


@njit(nogil=True, cache=True)
def _clamp01(x):
    if x < 0.0:
        return 0.0
    if x > 1.0:
        return 1.0
    return x


@njit(nogil=True, cache=True, inline="always")
def blinn_phong_factors(gx, gy, gz, hx, hy, hz, sp):
    """(diffuse factor, specular term) at a sample of gradient (gx, gy, gz) and half vector H, with
    the light and coefficients of the `ShadeParams` `sp`: the shaded colour is c * diffuse +
    specular; (1, 0) where |g| <= sp.gradient_threshold or is not finite."""
    mag = math.sqrt(gx * gx + gy * gy + gz * gz)
    if not (mag > sp.gradient_threshold) or not math.isfinite(mag):
        return 1.0, 0.0
    nx = -gx / mag
    ny = -gy / mag
    nz = -gz / mag
    ndl = nx * sp.lx + ny * sp.ly + nz * sp.lz
    if ndl < 0.0:  # two-sided lighting
        nx = -nx
        ny = -ny
        nz = -nz
        ndl = -ndl
    ndh = nx * hx + ny * hy + nz * hz
    return sp.ambient + sp.diffuse * ndl, sp.specular * max(ndh, 0.0) ** sp.power


@njit(nogil=True, cache=True)
def shade(sp, r, g, b, gx, gy, gz, hx, hy, hz):
    """Shaded colour of TF colour (r, g, b) at a sample with gradient (gx, gy, gz)."""
    k, spec = blinn_phong_factors(gx, gy, gz, hx, hy, hz, sp)
    return _clamp01(r * k + spec), _clamp01(g * k + spec), _clamp01(b * k + spec)
