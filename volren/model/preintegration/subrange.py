"""Incremental subrange integration (Lum, Wilson and Ma 2004): the exact table in O(n^2).

Entry (i, j), j = i + r, composites the bins m i ... m j - 1 of the value axis (m bins per table
step), each bin crossed over the same world length l = step / (r m). All entries of one
diagonal r share l, so their bins' opacities and colours are computed once per diagonal, and any
run of R = r m consecutive bins is a suffix of one block of R bins (blocks start at multiples of
R) composited over a prefix of the next. Per diagonal that is O(n_t) work for the block suffixes
and prefixes plus O(1) per entry, O(n n_t) in all, instead of O(n^2 n_t) for brute force.
Entries below the diagonal (front value above back value) are the same computation on the
reversed bin order.

Lighting ("weighted") tables additionally carry sum(g_k C_k T_k) with the global ramp g_k (bin
k's emission centre, in table-index units): the back-weighted colour of (i, j) is then
(G - i C) / (j - i) (Lum et al. section 4.3), with |j - i| >= 1 off the diagonal, so no division
blows up.

Composites are premultiplied colour C (with the opacity sum in channel 3) and transmittance T:
A over B = (C_A + T_A C_B, T_A T_B). An entry's opacity is 1 - T, which is non-decreasing in the
segment length under any rounding. A task computes a group of GROUP neighbouring diagonals so that
its writes into the table come in contiguous runs along the rows.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from volren.model.preintegration.segment_math import emission_centre

#: Diagonals per task: writes land as runs of GROUP entries (GROUP * 16 bytes) along a row.
GROUP = 16


@njit(nogil=True, cache=True)
def _bins(tau, color, ell, weighted, trans, col, centre):
    """Per-bin transmittance, premultiplied colour (opacity in channel 3) and emission centre
    for bins crossed over the length ell."""
    for k in range(tau.shape[0]):
        x = tau[k] * ell
        e = math.exp(-x)
        a = 1.0 - e
        trans[k] = e
        col[k, 0] = color[k, 0] * a
        col[k, 1] = color[k, 1] * a
        col[k, 2] = color[k, 2] * a
        col[k, 3] = a
        if weighted:
            centre[k] = emission_centre(x)


@njit(nogil=True, cache=True)
def _reverse(trans, col, centre, rtrans, rcol, rcentre):
    nb = trans.shape[0]
    for k in range(nb):
        rtrans[k] = trans[nb - 1 - k]
        for c in range(4):
            rcol[k, c] = col[nb - 1 - k, c]
    for k in range(centre.shape[0]):
        rcentre[k] = centre[nb - 1 - k]


@njit(nogil=True, cache=True)
def _block_composites(trans, col, big, sc, st, pc, pt):
    """For every bin q: sc/st the composite of bins q .. end of its block of `big` bins,
    pc/pt the composite of bins start of its block .. q."""
    nb = trans.shape[0]
    for b0 in range(0, nb, big):
        b1 = min(b0 + big, nb)
        c0 = c1 = c2 = c3 = 0.0
        t = 1.0
        for q in range(b1 - 1, b0 - 1, -1):
            e = trans[q]
            c0 = col[q, 0] + e * c0
            c1 = col[q, 1] + e * c1
            c2 = col[q, 2] + e * c2
            c3 = col[q, 3] + e * c3
            t = e * t
            sc[q, 0] = c0
            sc[q, 1] = c1
            sc[q, 2] = c2
            sc[q, 3] = c3
            st[q] = t
        c0 = c1 = c2 = c3 = 0.0
        t = 1.0
        for q in range(b0, b1):
            c0 += t * col[q, 0]
            c1 += t * col[q, 1]
            c2 += t * col[q, 2]
            c3 += t * col[q, 3]
            t *= trans[q]
            pc[q, 0] = c0
            pc[q, 1] = c1
            pc[q, 2] = c2
            pc[q, 3] = c3
            pt[q] = t


@njit(nogil=True, cache=True)
def _ramped_block_composites(trans, col, centre, m, big, sg, pg):
    """Like `_block_composites` for the colours weighted by the global ramp g_q."""
    nb = trans.shape[0]
    for b0 in range(0, nb, big):
        b1 = min(b0 + big, nb)
        c0 = c1 = c2 = c3 = 0.0
        for q in range(b1 - 1, b0 - 1, -1):
            e = trans[q]
            g = (q + centre[q]) / m
            c0 = g * col[q, 0] + e * c0
            c1 = g * col[q, 1] + e * c1
            c2 = g * col[q, 2] + e * c2
            c3 = g * col[q, 3] + e * c3
            sg[q, 0] = c0
            sg[q, 1] = c1
            sg[q, 2] = c2
            sg[q, 3] = c3
        c0 = c1 = c2 = c3 = 0.0
        t = 1.0
        for q in range(b0, b1):
            g = (q + centre[q]) / m * t
            c0 += g * col[q, 0]
            c1 += g * col[q, 1]
            c2 += g * col[q, 2]
            c3 += g * col[q, 3]
            t *= trans[q]
            pg[q, 0] = c0
            pg[q, 1] = c1
            pg[q, 2] = c2
            pg[q, 3] = c3


@njit(nogil=True, cache=True)
def _entries(m, n, r, weighted, sc, st, pc, pt, sg, pg, res, back):
    """Entries (i, i + r) of the bin order the composites were built in: res (n - r, 4) RGBA and,
    when weighted, back (n - r, 4) the back-weighted colour and white."""
    big = r * m
    for i in range(n - r):
        p = i * m
        q = p + big - 1
        if p % big == 0:  # the run is one whole block
            tf = st[p]
            a = 1.0 - tf
            res[i, 3] = a
            for c in range(3):
                res[i, c] = min(sc[p, c], a)  # equal in exact arithmetic for a white TF
            if weighted:
                for c in range(4):
                    v = res[i, c]
                    back[i, c] = min(max((sg[p, c] - i * v) / r, 0.0), v)
        else:
            tf = st[p]
            a = 1.0 - tf * pt[q]
            res[i, 3] = a
            for c in range(3):
                res[i, c] = min(sc[p, c] + tf * pc[q, c], a)
            if weighted:
                for c in range(4):
                    v = res[i, c]
                    back[i, c] = min(max((sg[p, c] + tf * pg[q, c] - i * v) / r, 0.0), v)


@njit(nogil=True, parallel=True, cache=True)
def subrange_tables(tau, color, m, n, lengths, weighted, out, out_back):
    """Off-diagonal entries of out (L, n, n, 4) float32 premultiplied RGBA, and when weighted of
    out_back (L, n, n, 4): back-weighted colour in 0..2 and back-weighted white in 3.

    tau (nb,) and color (nb, 3) are the TF's bin means (nb = m (n - 1)); lengths (L,) the
    segment lengths in world units. Diagonal entries are left for the caller (closed form)."""
    nb = tau.shape[0]
    nlen = lengths.shape[0]
    groups = (n - 2) // GROUP + 1
    wn = nb if weighted else 0
    for task in prange(nlen * groups):
        li = task // groups
        r0 = (task % groups) * GROUP + 1
        count = min(GROUP, n - r0)
        trans = np.empty(nb)
        col = np.empty((nb, 4))
        centre = np.empty(wn)
        rtrans = np.empty(nb)
        rcol = np.empty((nb, 4))
        rcentre = np.empty(wn)
        sc = np.empty((nb, 4))
        st = np.empty(nb)
        pc = np.empty((nb, 4))
        pt = np.empty(nb)
        sg = np.empty((wn, 4))
        pg = np.empty((wn, 4))
        res = np.empty((2, count, n, 4))
        back = np.empty((2, count, n if weighted else 0, 4))  # empty unless weighted
        for d in range(count):
            r = r0 + d
            _bins(tau, color, lengths[li] / (r * m), weighted, trans, col, centre)
            _reverse(trans, col, centre, rtrans, rcol, rcentre)
            for side in range(2):
                tr = trans if side == 0 else rtrans
                cl = col if side == 0 else rcol
                ce = centre if side == 0 else rcentre
                _block_composites(tr, cl, r * m, sc, st, pc, pt)
                if weighted:
                    _ramped_block_composites(tr, cl, ce, m, r * m, sg, pg)
                _entries(m, n, r, weighted, sc, st, pc, pt, sg, pg, res[side, d], back[side, d])
        # write: forward entry i of diagonal r is (i, i + r); reversed entry i is (n-1-i, n-1-i-r)
        for i in range(n - r0):
            for d in range(min(count, n - r0 - i)):
                r = r0 + d
                for c in range(4):
                    out[li, i, i + r, c] = res[0, d, i, c]
                    out[li, n - 1 - i, n - 1 - i - r, c] = res[1, d, i, c]
                if weighted:
                    for c in range(4):
                        out_back[li, i, i + r, c] = back[0, d, i, c]
                        out_back[li, n - 1 - i, n - 1 - i - r, c] = back[1, d, i, c]
