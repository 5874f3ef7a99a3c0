"""The link model's compiled tick (:mod:`firefleet.sim.link`): the shared channel, each
directed pair's loss and delay, the messages in flight and what each receiver holds."""

from __future__ import annotations

import math

import numba

from firefleet._typing import FloatArray, IntArray

SQRT1_2 = 1.0 / math.sqrt(2.0)


@numba.njit(cache=True)
def packet_error_one(
    d_m: float, range_m: float, exponent: float, sigma_db: float, wall_db: float
) -> float:  # pragma: no cover - compiled
    """Packet error rate at ``d_m`` (log-distance path loss with log-normal shadowing):
    ``Phi(-(10 n log10(range / d) - wall_db) / sigma)``; 1 beyond ``range_m``; a hard
    step at ``range_m`` without shadowing."""
    if d_m > range_m:
        return 1.0
    margin_db = 10.0 * exponent * math.log10(range_m / max(d_m, 1e-9)) - wall_db
    if sigma_db <= 0.0:
        return 0.0 if margin_db > 0.0 else 1.0
    return 0.5 * math.erfc(margin_db / sigma_db * SQRT1_2)


@numba.njit(cache=True)
def link_tick(
    k: int,
    dt: float,
    params: FloatArray,
    payload: FloatArray,
    send: IntArray,
    pose: FloatArray,
    walls: FloatArray,
    order: IntArray,
    uniform: FloatArray,
    normal: FloatArray,
    queue_tick: IntArray,
    queue_val: FloatArray,
    queue_len: IntArray,
    channel: FloatArray,
    bad: IntArray,
    flight_t: FloatArray,
    flight_i: IntArray,
    flight_val: FloatArray,
    n_flight: IntArray,
    held_val: FloatArray,
    held_tick: FloatArray,
    counters: FloatArray,
) -> None:  # pragma: no cover - compiled
    """One tick of the link, in place: the broadcasts generated at tick ``k - 1`` join
    their senders' queues, the channel carries what it can up to ``k dt``, each
    receiver gets or loses each frame, and what has arrived by ``k dt`` is held.

    Parameters
    ----------
    params : ndarray, shape (11,)
        airtime [s], frame gap [s], delay [s], jitter [s], loss, burst length, range
        [m], path-loss exponent, shadowing [dB], wall attenuation [dB per cell], queue
        capacity [messages].
    payload : ndarray, shape (N, M)
        The values each robot broadcast at tick ``k - 1``.
    send : ndarray of int, shape (N,)
        1 where robot i broadcast at tick ``k - 1``.
    pose : ndarray, shape (N, >= 2)
        True positions [m] (the channel is physical).
    walls : ndarray, shape (N, N) or (1, 1)
        Occupied cells between each pair (a map), or a (1, 1) zero.
    order : ndarray of int, shape (N,)
        The senders' contention order this tick (a random permutation).
    uniform, normal : ndarray, shape (F, N, 2)
        Random numbers for at most F frames this tick.
    queue_tick, queue_val, queue_len
        Each sender's FIFO (N, Q) of generation ticks and (N, Q, M) values, and its
        length (N,).
    channel : ndarray, shape (1,)
        When the channel is next free [s].
    bad : ndarray of int, shape (N, N)
        Gilbert-Elliott state of each directed pair (1: bad).
    flight_t, flight_i, flight_val, n_flight
        Frames in flight: arrival time [s] (C,), (sender, receiver, generation tick)
        (C, 3), values (C, M), and their count (1,).
    held_val, held_tick
        What each receiver holds from each sender: values (N, N, M) and the tick it was
        sent at (N, N; an integer as a float), -1 for nothing yet.
    counters : ndarray, shape (4,)
        Messages sent, lost (channel, range or queue), dropped at a full queue, frames
        put on the air (cumulative).
    """
    n = payload.shape[0]
    m = payload.shape[1]
    airtime, gap, delay, jitter = params[0], params[1], params[2], params[3]
    loss, burst, range_m, exponent = params[4], params[5], params[6], params[7]
    sigma, wall_db, capacity = params[8], params[9], int(params[10])
    has_walls = walls.shape[0] == n
    # Gilbert-Elliott: r = P(bad -> good) = 1 / burst; p = P(good -> bad) from the mean loss
    r = 1.0 / burst
    p = loss * r / (1.0 - loss) if loss < 1.0 else 1.0
    t_gen = (k - 1) * dt
    t_now = k * dt
    # 1. this tick's broadcasts join their queues (a full queue drops the new one)
    for i in range(n):
        if send[i] == 0:
            continue
        # the sender hears itself at once
        held_tick[i, i] = float(k - 1)
        for c in range(m):
            held_val[i, i, c] = payload[i, c]
        if queue_len[i] >= capacity:
            counters[0] += n - 1
            counters[1] += n - 1
            counters[2] += 1
            continue
        q = queue_len[i]
        queue_tick[i, q] = k - 1
        for c in range(m):
            queue_val[i, q, c] = payload[i, c]
        queue_len[i] = q + 1
    # 2. the channel: senders in contention order, one frame each per round, until the
    # channel is busy past this tick
    frames = 0
    free = max(channel[0], t_gen)
    progress = True
    while progress and free < t_now and frames < uniform.shape[0]:
        progress = False
        for o in range(n):
            i = order[o]
            if queue_len[i] == 0 or free >= t_now or frames >= uniform.shape[0]:
                continue
            progress = True
            start = max(free, queue_tick[i, 0] * dt)
            end = start + airtime
            free = end + gap
            gen = queue_tick[i, 0]
            counters[3] += 1
            for j in range(n):
                if j == i:
                    continue
                counters[0] += 1
                # the pair's loss process (Bernoulli when burst == 1)
                u = uniform[frames, j, 0]
                if burst <= 1.0:
                    lost = u < loss
                else:
                    if bad[i, j] == 1:
                        bad[i, j] = 0 if u < r else 1
                    else:
                        bad[i, j] = 1 if u < p else 0
                    lost = bad[i, j] == 1
                # range, shadowing and walls
                if not lost and range_m < math.inf:
                    dx = pose[j, 0] - pose[i, 0]
                    dy = pose[j, 1] - pose[i, 1]
                    d = math.sqrt(dx * dx + dy * dy)
                    w = walls[i, j] * wall_db if has_walls else 0.0
                    if d > range_m:
                        lost = True
                    else:
                        margin = 10.0 * exponent * math.log10(range_m / max(d, 1e-9)) - w
                        lost = margin + sigma * normal[frames, j, 0] < 0.0
                if lost:
                    counters[1] += 1
                    continue
                arrive = end + delay + max(jitter * normal[frames, j, 1], -delay)
                f = n_flight[0]
                flight_t[f] = arrive
                flight_i[f, 0] = i
                flight_i[f, 1] = j
                flight_i[f, 2] = gen
                for c in range(m):
                    flight_val[f, c] = queue_val[i, 0, c]
                n_flight[0] = f + 1
            # pop the head of the queue
            for q in range(1, queue_len[i]):
                queue_tick[i, q - 1] = queue_tick[i, q]
                for c in range(m):
                    queue_val[i, q - 1, c] = queue_val[i, q, c]
            queue_len[i] -= 1
            frames += 1
    channel[0] = free
    # 3. what has arrived by now is held (the newest generation wins)
    f = 0
    while f < n_flight[0]:
        if flight_t[f] <= t_now + 1e-12:
            i, j, gen = flight_i[f, 0], flight_i[f, 1], flight_i[f, 2]
            if gen > held_tick[j, i]:
                held_tick[j, i] = float(gen)
                for c in range(m):
                    held_val[j, i, c] = flight_val[f, c]
            last = n_flight[0] - 1
            flight_t[f] = flight_t[last]
            flight_i[f, 0], flight_i[f, 1], flight_i[f, 2] = (
                flight_i[last, 0],
                flight_i[last, 1],
                flight_i[last, 2],
            )
            for c in range(m):
                flight_val[f, c] = flight_val[last, c]
            n_flight[0] = last
        else:
            f += 1
