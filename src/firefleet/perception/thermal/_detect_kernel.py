"""The compiled per-frame work of :func:`firefleet.perception.thermal.detect`.

One frame is 80 x 60 pixels: SciPy's and NumPy's calls on it (median filter, grey
opening, labelling, per-label reductions, percentiles) cost more in their Python
set-up than in their arithmetic. These kernels do the same arithmetic in one compiled
pass each:

- :func:`filter_frame`: the column offsets removed (:func:`_frames.destripe`'s steps, the
  offsets' mean and linear trend removed by the closed-form least-squares line, equal to
  ``np.polyfit``'s to round-off), the 3 x 3 median, fire-hot pixels kept as they were;
- :func:`find_regions`: the frame's median, the grey opening along each row (van Herk /
  Gil-Werman running minimum and maximum, with SciPy's window alignment for an even
  length and its ``mode="nearest"`` border), the hysteresis mask, the 8-connected
  labels (numbered in raster order of their first pixel, as ``scipy.ndimage.label``),
  and per label its peak contrast, area and bounding box;
- :func:`describe_region`: one region's peak, mean, centroid, surround, core and the
  sub-pixel extent of its band-radiance fill (``_detect._profiles``), and the median
  stereo depth in it.

Sums are NumPy's pairwise sums (:func:`pairwise_sum`, the same blocking as NumPy's
``add.reduce`` on a contiguous float64 array), medians NumPy's, the percentile NumPy's
linear interpolation, so the compiled detector reproduces the NumPy one
(``tests/perception/test_detect_kernel.py`` holds that reference and compares).

References
----------
M. van Herk, "A fast algorithm for local minimum and maximum filters on rectangular
and octagonal kernels", Pattern Recognition Letters 13(7), 1992.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from firefleet._typing import FloatArray
from firefleet.perception.thermal._frames import _column_steps, _median3_nearest
from firefleet.perception.thermal._select import order_pair
from firefleet.perception.thermal._table import interp_table

__all__ = ["describe_region", "filter_frame", "find_regions", "pairwise_sum"]

N_STATS = 16
"""Columns of :func:`describe_region`'s result (see there)."""


@numba.njit(cache=True)
def pairwise_sum(a: FloatArray) -> float:  # pragma: no cover - compiled
    """Sum of a contiguous 1-D float64 array in NumPy's pairwise order (bit for bit).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal._detect_kernel import pairwise_sum
    >>> x = np.random.default_rng(0).normal(size=1000)
    >>> bool(pairwise_sum(x) == x.sum())
    True
    """
    n = a.size
    if n < 8:
        s = -0.0
        for i in range(n):
            s += a[i]
        return s
    if n <= 128:
        r0, r1, r2, r3 = a[0], a[1], a[2], a[3]
        r4, r5, r6, r7 = a[4], a[5], a[6], a[7]
        i = 8
        while i < n - (n % 8):
            r0 += a[i]
            r1 += a[i + 1]
            r2 += a[i + 2]
            r3 += a[i + 3]
            r4 += a[i + 4]
            r5 += a[i + 5]
            r6 += a[i + 6]
            r7 += a[i + 7]
            i += 8
        s = float(((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7)))
        while i < n:
            s += a[i]
            i += 1
        return s
    n2 = n // 2
    n2 -= n2 % 8
    return pairwise_sum(a[:n2]) + pairwise_sum(a[n2:])


@numba.njit(cache=True)
def filter_frame(
    raw: FloatArray, do_destripe: bool, max_step: float, median3: bool, hot_c: float
) -> tuple[FloatArray, FloatArray]:  # pragma: no cover - compiled
    """(destriped frame, filtered frame): ``detect``'s steps 1 (module notes)."""
    h, w = raw.shape
    if do_destripe:
        steps = _column_steps(raw, max_step)
        off = np.empty(w)
        off[0] = 0.0
        for c in range(1, w):
            off[c] = off[c - 1] + steps[c - 1]
        xm = 0.5 * (w - 1)
        ym = 0.0
        for c in range(w):
            ym += off[c]
        ym /= w
        sxy = 0.0
        sxx = 0.0
        for c in range(w):
            sxy += (c - xm) * (off[c] - ym)
            sxx += (c - xm) * (c - xm)
        slope = sxy / sxx
        icpt = ym - slope * xm
        flat = np.empty_like(raw)
        for c in range(w):
            o = off[c] - (slope * c + icpt)
            for r in range(h):
                flat[r, c] = raw[r, c] - o
    else:
        flat = raw.copy()
    f = _median3_nearest(flat) if median3 else flat.copy()
    for r in range(h):
        for c in range(w):
            if flat[r, c] >= hot_c:
                f[r, c] = flat[r, c]
    return flat, f


@numba.njit(cache=True)
def _running_columns(
    src: FloatArray,
    lo: int,
    size: int,
    use_max: bool,
    out: FloatArray,
    pad: FloatArray,
    g: FloatArray,
    hh: FloatArray,
) -> None:  # pragma: no cover - compiled
    """For every row of a frame at once, ``out[c]`` = min (or max) of
    ``row[clip(c + lo .. c + lo + size - 1)]`` (van Herk: running extremes from each
    block's start ``g`` and to its end ``hh``). The frame is held transposed (``src``
    and ``out`` (W, H), the work buffers (W + size - 1, H)): the rows side by side in
    memory, so that the compiler runs several at a time, each row's minima taken in
    the order of a row by itself."""
    w, h = src.shape
    m = w + size - 1
    sign = -1.0 if use_max else 1.0  # a maximum is the minimum of the negated values
    for j in range(m):
        jj = min(max(j + lo, 0), w - 1)
        for r in range(h):
            pad[j, r] = sign * src[jj, r]
    for b0 in range(0, m, size):
        b1 = min(b0 + size, m)
        for r in range(h):
            g[b0, r] = pad[b0, r]
        for j in range(b0 + 1, b1):
            for r in range(h):
                g[j, r] = min(g[j - 1, r], pad[j, r])
        for r in range(h):
            hh[b1 - 1, r] = pad[b1 - 1, r]
        for j in range(b1 - 2, b0 - 1, -1):
            for r in range(h):
                hh[j, r] = min(hh[j + 1, r], pad[j, r])
    for c in range(w):
        for r in range(h):
            out[c, r] = sign * min(hh[c, r], g[c + size - 1, r])


@numba.njit(cache=True)
def find_regions(
    f: FloatArray, fiery_c: float, warm_k: float, size: int
) -> tuple[
    float, FloatArray, np.ndarray, np.ndarray, FloatArray, np.ndarray, np.ndarray
]:  # pragma: no cover - compiled
    """``detect``'s step 2: (background [C], contrast (H, W), low (H, W) bool, labels
    (H, W) int32, per label: top contrast (inf for a fiery one), area [px], bounding
    box ``(r0, c0, r1, c1)``)."""
    h, w = f.shape
    flat = f.ravel()  # np.median's: the mean of the middle two of an even count
    lower, upper = order_pair(
        flat, flat.size, flat.size // 2, np.empty(1024, np.int64), np.empty(flat.size)
    )
    background = upper if flat.size % 2 == 1 else (lower + upper) / 2
    lo_e = -(size // 2)
    lo_d = -(size - 1 - size // 2)
    # the opening along each row (erosion, then dilation), all rows at once
    f_t = np.empty((w, h))
    for r in range(h):
        for c in range(w):
            f_t[c, r] = f[r, c]
    ero = np.empty((w, h))
    opened_t = np.empty((w, h))
    pad = np.empty((w + size - 1, h))
    g = np.empty((w + size - 1, h))
    hh = np.empty((w + size - 1, h))
    _running_columns(f_t, lo_e, size, False, ero, pad, g, hh)
    _running_columns(ero, lo_d, size, True, opened_t, pad, g, hh)
    contrast = np.empty((h, w))
    for r in range(h):
        for c in range(w):
            contrast[r, c] = f[r, c] - opened_t[c, r]
    low = np.zeros((h, w), dtype=np.bool_)
    for r in range(h):
        for c in range(w):
            low[r, c] = contrast[r, c] >= 0.5 * warm_k or f[r, c] >= fiery_c
    labels = np.zeros((h, w), dtype=np.int32)
    stack = np.empty(h * w, dtype=np.int64)
    top = np.empty(h * w)
    area = np.empty(h * w, dtype=np.int64)
    box = np.empty((h * w, 4), dtype=np.int64)
    n = 0
    for r in range(h):
        for c in range(w):
            if not low[r, c] or labels[r, c] != 0:
                continue
            n += 1
            labels[r, c] = n
            sp = 0
            stack[0] = r * w + c
            sp = 1
            t = -np.inf
            a = 0
            r0, c0, r1, c1 = r, c, r + 1, c + 1
            while sp > 0:
                sp -= 1
                p = stack[sp]
                pr = p // w
                pc = p % w
                v = np.inf if f[pr, pc] >= fiery_c else contrast[pr, pc]
                t = max(t, v)
                a += 1
                r0 = min(r0, pr)
                c0 = min(c0, pc)
                r1 = max(r1, pr + 1)
                c1 = max(c1, pc + 1)
                for dr in range(-1, 2):
                    qr = pr + dr
                    if qr < 0 or qr >= h:
                        continue
                    for dc in range(-1, 2):
                        qc = pc + dc
                        if qc < 0 or qc >= w or not low[qr, qc] or labels[qr, qc] != 0:
                            continue
                        labels[qr, qc] = n
                        stack[sp] = qr * w + qc
                        sp += 1
            top[n - 1] = t
            area[n - 1] = a
            box[n - 1, 0] = r0
            box[n - 1, 1] = c0
            box[n - 1, 2] = r1
            box[n - 1, 3] = c1
    return background, contrast, low, labels, top[:n].copy(), area[:n].copy(), box[:n].copy()


@numba.njit(cache=True)
def _percentile_linear(sorted_v: FloatArray, q: float) -> float:  # pragma: no cover - compiled
    """NumPy's ``percentile(..., method="linear")`` of sorted values."""
    n = sorted_v.size
    idx = q / 100.0 * (n - 1)
    i = math.floor(idx)
    j = min(i + 1, n - 1)
    g = idx - i
    a = float(sorted_v[i])
    b = float(sorted_v[j])
    d = b - a
    if g >= 0.5:
        return float(b - d * (1.0 - g))
    return float(a + d * g)


@numba.njit(cache=True)
def describe_region(
    f: FloatArray,
    labels: np.ndarray,
    low: np.ndarray,
    lab: int,
    box: np.ndarray,
    background: float,
    fire_min_c: float,
    fire_contrast_min_c: float,
    fire_contrast_k: float,
    table_c: FloatArray,
    table_rad: FloatArray,
    depth: FloatArray,
    has_depth: bool,
) -> FloatArray:  # pragma: no cover - compiled
    """One region's numbers (``_detect._describe`` and ``_measure`` up to the camera):

    0 peak, 1 mean [C], 2 area [px], 3-4 centroid row, col [px], 5 surround [C],
    6 is fire (0/1), 7 profile found (0/1), 8-11 sub-pixel centre row, col and extent
    height, width [px], 12 stereo found (0/1), 13 median depth [m], 14 its spread [m]
    (1.4826 MAD), 15 the radiance table's range exceeded (0/1: the caller raises).
    """
    h, w = f.shape
    out = np.zeros(N_STATS)
    r0, c0, r1, c1 = box[0], box[1], box[2], box[3]
    nv = 0
    for r in range(r0, r1):
        for c in range(c0, c1):
            if labels[r, c] == lab:
                nv += 1
    values = np.empty(nv)
    rows = np.empty(nv)
    cols = np.empty(nv)
    k = 0
    for r in range(r0, r1):
        for c in range(c0, c1):
            if labels[r, c] == lab:
                values[k] = f[r, c]
                rows[k] = r - r0
                cols[k] = c - c0
                k += 1
    peak = values.max()
    mean = pairwise_sum(values) / nv
    out[0] = peak
    out[1] = mean
    out[2] = nv
    out[3] = r0 + pairwise_sum(rows) / nv
    out[4] = c0 + pairwise_sum(cols) / nv
    ring = 3
    or0, or1 = max(r0 - ring, 0), min(r1 + ring, h)
    oc0, oc1 = max(c0 - ring, 0), min(c1 + ring, w)
    around = np.empty((or1 - or0) * (oc1 - oc0))
    m = 0
    for r in range(or0, or1):
        for c in range(oc0, oc1):
            if not low[r, c]:
                around[m] = f[r, c]
                m += 1
    surround = np.median(around[:m]) if m > 0 else background
    out[5] = surround
    is_fire = peak >= fire_min_c or (
        peak >= fire_contrast_min_c and peak - surround >= fire_contrast_k
    )
    out[6] = 1.0 if is_fire else 0.0
    core = peak if is_fire else _percentile_linear(np.sort(values), 75.0)
    # the band-radiance fill of a window one pixel wider than the box
    wr0, wr1 = max(r0 - 1, 0), min(r1 + 1, h)
    wc0, wc1 = max(c0 - 1, 0), min(c1 + 1, w)
    t_lo, t_hi = table_c[0], table_c[-1]
    core = max(core, surround + 1e-3)
    if not (t_lo <= surround <= t_hi and t_lo <= core <= t_hi):
        out[15] = 1.0
        return out
    l_bg = interp_table(surround, table_c, table_rad)
    l_core = interp_table(core, table_c, table_rad)
    hw, ww = wr1 - wr0, wc1 - wc0
    frac = np.zeros((hw, ww))
    for r in range(wr0, wr1):
        for c in range(wc0, wc1):
            v = f[r, c]
            if not t_lo <= v <= t_hi:
                out[15] = 1.0
                return out
            near = False
            for dr in range(-1, 2):
                qr = r + dr
                if qr < wr0 or qr >= wr1:
                    continue
                for dc in range(-1, 2):
                    qc = c + dc
                    if wc0 <= qc < wc1 and labels[qr, qc] == lab:
                        near = True
            x = (interp_table(v, table_c, table_rad) - l_bg) / (l_core - l_bg)
            x = min(max(x, 0.0), 1.0)
            frac[r - wr0, c - wc0] = x if near else 0.0
    col_prof = np.empty(ww)
    for c in range(ww):
        col_prof[c] = frac[:, c].max()
    wsum = pairwise_sum(col_prof)
    if wsum > 0:
        jw = np.empty(ww)
        for c in range(ww):
            jw[c] = c * col_prof[c]
        cc = pairwise_sum(jw) / wsum
        jc = int(min(max(np.rint(cc), 0.0), ww - 1.0))
        row_prof = np.empty(hw)
        den = max(col_prof[jc], 1e-6)
        for r in range(hw):
            row_prof[r] = min(max(frac[r, jc] / den, 0.0), 1.0)
        hsum = pairwise_sum(row_prof)
        if hsum > 0:
            iw = np.empty(hw)
            for r in range(hw):
                iw[r] = r * row_prof[r]
            rc = pairwise_sum(iw) / hsum
            out[7] = 1.0
            out[8] = wr0 + rc
            out[9] = wc0 + cc
            out[10] = hsum
            out[11] = wsum
    if has_depth:
        d = np.empty(nv)
        m = 0
        for r in range(r0, r1):
            for c in range(c0, c1):
                if labels[r, c] == lab:
                    z = depth[r, c]
                    if np.isfinite(z) and z > 0:
                        d[m] = z
                        m += 1
        if m > 0:
            z = np.median(d[:m])
            dev = np.abs(d[:m] - z)
            out[12] = 1.0
            out[13] = z
            out[14] = 1.4826 * np.median(dev)
    return out
