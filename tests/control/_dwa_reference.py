"""The dynamic window as it was before the obstacle search was pruned: every candidate
arc against every obstacle (the brute-force reference of tests/control/test_dwa_kernel.py)."""

# mypy: ignore-errors
from __future__ import annotations

import math

import numba
import numpy as np

FloatArray = np.ndarray
BoolArray = np.ndarray


@numba.njit(cache=False)
def _arc_xy(x: float, y: float, th: float, v: float, w: float, t: float) -> tuple[float, float]:
    if abs(w) < 1e-9:
        return x + v * t * math.cos(th), y + v * t * math.sin(th)
    return (
        x + v / w * (math.sin(th + w * t) - math.sin(th)),
        y - v / w * (math.cos(th + w * t) - math.cos(th)),
    )  # pragma: no cover - compiled


@numba.njit(cache=False)
def _evaluate(
    pose: FloatArray,
    v: float,
    w: float,
    obs: FloatArray,
    rad: FloatArray,
    radius: float,
    horizon: float,
    n_steps: int,
) -> tuple[float, float]:  # pragma: no cover - compiled
    """(clearance [m], distance before moving into contact [m]; inf if none)."""
    c0 = np.inf
    cmin = np.inf
    travel = np.inf
    for k in range(n_steps + 1):
        t = horizon * k / n_steps
        px, py = _arc_xy(pose[0], pose[1], pose[2], v, w, t)
        c = np.inf
        for m in range(obs.shape[0]):
            d = math.hypot(obs[m, 0] - px, obs[m, 1] - py) - rad[m] - radius
            c = min(c, d)
        if k == 0:
            c0 = c
        cmin = min(cmin, c)
        if c < 0.0 and c < c0 - 1e-9 and travel == np.inf:
            travel = max(v * horizon * (k - 1) / n_steps, 0.0)
    return cmin, travel


@numba.njit(cache=False)
def _dwa_one(
    pose: FloatArray,
    v0: float,
    w0: float,
    v_ref: float,
    w_ref: float,
    obs: FloatArray,
    rad: FloatArray,
    dt: float,
    vw: float,
    aw: float,
    axle: float,
    radius: float,
    horizon: float,
    n_v: int,
    n_w: int,
    n_steps: int,
    c_cap: float,
    c_weight: float,
    turn: bool,
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    half = axle / 2.0
    v_max = vw
    w_max = vw / half
    # the last command, clipped into the speed limits (v >= 0, |v| + |w| L/2 <= v_w)
    v0 = min(max(v0, 0.0), v_max)
    w_lim = (vw - v0) / half
    w0 = min(max(w0, -w_lim), w_lim)
    da = aw * dt
    v_lo = max(0.0, v0 - da)
    v_hi = min(v_max, v0 + da)
    # the reference projected into the window: speed first, then turn rate
    vr = min(max(v_ref, v_lo), v_hi)
    b = (da - abs(vr - v0)) / half
    lim = (vw - vr) / half
    lo = max(w0 - b, -lim)
    hi = min(w0 + b, lim)
    if lo > hi:
        vr = v0
        b = da / half
        lim = (vw - vr) / half
        lo = max(w0 - b, -lim)
        hi = min(w0 + b, lim)
    wr = min(max(w_ref, lo), hi)
    best = -np.inf
    best_v = v_lo
    best_w = w0
    best_c = -np.inf
    fb_score = -np.inf
    fb_v = v_lo
    fb_w = w0
    fb_c = -np.inf
    moving = False  # an admissible command with v > 0
    for iv in range(n_v + 1):
        if iv < n_v:
            v = v_lo + (v_hi - v_lo) * iv / (n_v - 1)
            b = (da - abs(v - v0)) / half
            lim = (vw - v) / half
            lo = max(w0 - b, -lim)
            hi = min(w0 + b, lim)
            if lo > hi + 1e-12:
                continue
            count = n_w
        else:
            v = vr
            count = 1
        for iw in range(count):
            w = (lo + (hi - lo) * iw / (count - 1) if hi > lo else lo) if iv < n_v else wr
            c, travel = _evaluate(pose, v, w, obs, rad, radius, horizon, n_steps)
            if travel != np.inf and v > math.sqrt(2.0 * aw * travel) + 1e-12:
                # inadmissible; remembered in case nothing is: the slowest, then the
                # clearest
                fallback = -v * 1e6 + min(c, 1e3)
                if fallback > fb_score:
                    fb_score = fallback
                    fb_v = v
                    fb_w = w
                    fb_c = c
                continue
            score = (
                -(((v - v_ref) / v_max) ** 2)
                - ((w - w_ref) / w_max) ** 2
                + c_weight * min(c, c_cap) / c_cap
            )
            if score > best:
                best = score
                best_v = v
                best_w = w
                best_c = c
            if v > 0.0:
                moving = True
    if turn and not moving and v_lo == 0.0:
        # a stuck robot with no speed admissible, only turns in place: the asked turn,
        # clipped into the window, is tried too (``dwa_command``'s ``stuck``)
        b = (da - v0) / half  # the window's turn rates at v = 0 (v0 <= da here)
        lim = vw / half
        w = min(max(w_ref, max(w0 - b, -lim)), min(w0 + b, lim))
        c, _ = _evaluate(pose, 0.0, w, obs, rad, radius, horizon, n_steps)
        score = (
            -((v_ref / v_max) ** 2) - ((w - w_ref) / w_max) ** 2 + c_weight * min(c, c_cap) / c_cap
        )
        if score > best:
            best = score
            best_v = 0.0
            best_w = w
            best_c = c
    if best == -np.inf:  # nothing admissible: brake as hard as the window allows
        return fb_v, fb_w, fb_c
    return best_v, best_w, best_c


@numba.njit(cache=False)
def _dwa_batch(
    pose: FloatArray,
    last: FloatArray,
    ref: FloatArray,
    obs: FloatArray,
    rad: FloatArray,
    dt: float,
    vw: float,
    aw: float,
    axle: float,
    radius: float,
    horizon: float,
    n_v: int,
    n_w: int,
    n_steps: int,
    c_cap: float,
    c_weight: float,
    turn: BoolArray,
) -> FloatArray:  # pragma: no cover - compiled
    out = np.empty((pose.shape[0], 3))
    for i in range(pose.shape[0]):
        v, w, c = _dwa_one(
            pose[i],
            last[i, 0],
            last[i, 1],
            ref[i, 0],
            ref[i, 1],
            obs[i],
            rad[i],
            dt,
            vw,
            aw,
            axle,
            radius,
            horizon,
            n_v,
            n_w,
            n_steps,
            c_cap,
            c_weight,
            bool(turn[i]),
        )
        out[i, 0] = v
        out[i, 1] = w
        out[i, 2] = c
    return out
