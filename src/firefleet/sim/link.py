"""The team's wireless link, a stage of the world loop (deliverable section 2.5).

The deliverable assumes "ideal communication link between all the robots" and names
the radios it would use: "a Xbee, ZigBee or NRF module". :class:`LinkModel` is such a
link, seeded, applied per directed pair of robots to every message that crosses it:

- **bandwidth and airtime**: each broadcast is one frame on one shared channel, of
  the encoded size of the team's message (:func:`firefleet.net.encoded_size` of a
  ``State``, 81 B, header included) plus the radio's framing; its airtime is
  ``bits / rate``, and frames follow each other with the radio's mean gap (inter-frame
  space and random backoff). Each robot queues its broadcasts (a few frames, as the
  radios' buffers do); senders contend in a random order each tick; a team that talks
  more than the channel carries sees its messages wait (queueing delay) and the
  newest dropped at a full queue;
- **loss**: independent (Bernoulli) with probability ``loss``, or bursty
  (Gilbert-Elliott [2]_: a good state that loses nothing and a bad one that loses
  everything, the chain advanced per frame on each directed pair; mean burst length
  ``burst_length`` = ``1 / r``, ``r`` the bad-to-good probability, and the
  good-to-bad ``p = loss r / (1 - loss)`` so that the mean loss is ``loss``);
- **range**: log-distance path loss with log-normal shadowing [1]_: a frame reaches
  a receiver at distance ``d`` if ``10 n log10(range_m / d) - walls + sigma z > 0``
  (``z`` standard normal per frame and receiver), i.e. the mean received power falls
  to the receiver's sensitivity at ``range_m``; packet error rate
  ``Phi(-(10 n log10(range_m / d) - walls) / sigma)`` (:func:`packet_error_rate`);
  nothing arrives beyond ``range_m``. With a map, every occupied cell the straight
  line between the two robots crosses attenuates by ``wall_db`` (:func:`wall_cells`);
- **latency and jitter**: a delivered frame arrives ``delay_s`` after its airtime
  ends, plus Gaussian jitter of deviation ``jitter_s`` (the total latency never below
  the airtime).

Receivers hold the last value from each sender with its age: the inbox the decision
sees holds, for each key the team broadcasts, an (N, N) array (row ``i``: what robot
``i`` holds from each robot; its own broadcast at once) and ``sent_tick`` (N, N), the
tick each value was sent at (-1: nothing heard yet; its age at tick ``k`` is
``(k - sent_tick) dt``, :func:`ages`). The link itself touches only the pairs a frame
crosses, never all N^2 of them at a tick. The controllers predict from the last known
rate and flag values older than a timeout (:mod:`firefleet.control.coordination`).

Presets (:data:`PRESETS`): the data sheets' rate, transmit power and receiver
sensitivity; the range is the link budget (power - sensitivity) spent by the
log-distance law from the 1 m free-space loss at 2.4 GHz (40 dB) with exponent
``n = 3`` (in buildings, [1]_ Table 4.2) and shadowing deviation 4 dB ([1]_ 4.9.2):
``range = 10 ** ((P_tx - S - 40) / 30)``.

- ``xbee``: Digi XBee 802.15.4 (Series 1) data sheet (90000982): IEEE 802.15.4, 250
  kbit/s, 0 dBm, -92 dBm: 54.1 m. Framing 17 B (PHY preamble, SFD and length 6 B, MAC
  header and FCS 11 B), frame gap 1.76 ms (LIFS 640 us and the mean CSMA backoff
  3.5 x 320 us of 802.15.4-2006), 10 ms latency (the module's serial interface at
  115,200 baud carries 81 B in 7 ms).
- ``zigbee``: Digi XBee ZigBee (S2C) data sheet: 250 kbit/s, +5 dBm, -100 dBm:
  146 m; framing 33 B (adds the ZigBee network and APS headers, 8 B each); frame gap
  1.76 ms; 15 ms latency (the network layer's processing besides the serial link).
- ``nrf24``: Nordic nRF24L01+ product specification v1.0: 250 kbit/s at -94 dBm
  (2 Mbit/s at -82 dBm: ``rate_bit_s: 2e6, range_m: 25``), 0 dBm: 63 m; framing 9 B
  (preamble 1, address 5, PCF 9 bits, CRC 2), frame gap 130 us (the PLL settling of
  TX mode) plus ARD-free broadcast; 1 ms latency (SPI).
- ``wifi``: Espressif ESP32 data sheet, 802.11g at 54 Mbit/s: +14 dBm, -72 dBm:
  32 m; framing 64 B (MAC header 24, FCS 4, LLC/SNAP 8, IP and UDP 28) and the PHY
  preamble 20 us; frame gap 96 us (DIFS 28 us and the mean backoff 7.5 x 9 us); 2 ms
  latency.
- every radio preset broadcasts at 20 Hz (``period_s: 0.05``); ``period_s`` sets it
  (at every 10 ms tick a team of three already overloads an XBee channel).
- ``ideal``: infinite rate, no loss, no delay, no range limit: the world loop's ideal
  link, bit for bit.

References
----------
.. [1] T. S. Rappaport, *Wireless Communications: Principles and Practice*, 2nd ed.,
   Prentice Hall, 2002, sections 4.9 (log-distance path loss, log-normal shadowing).
.. [2] E. N. Gilbert, "Capacity of a burst-noise channel", Bell Syst. Tech. J. 39,
   1253-1265, 1960; E. O. Elliott, "Estimates of error rates for codes on burst-noise
   channels", Bell Syst. Tech. J. 42, 1977-1997, 1963.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.special import erfc

from firefleet._typing import FloatArray, IntArray
from firefleet.errors import InputError
from firefleet.net.messages import State, encoded_size
from firefleet.scenarios._network import LinkSpec
from firefleet.sim._kernels._link import link_tick
from firefleet.world import OccupancyGrid

__all__ = [
    "PRESETS",
    "LinkModel",
    "LinkParams",
    "LinkState",
    "ages",
    "message_bytes",
    "packet_error_rate",
    "wall_cells",
]


def ages(sent_tick: FloatArray, step: int, dt_s: float) -> FloatArray:
    """The ages [s] of held values sent at ``sent_tick`` (-1: none, inf), at tick ``step``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.link import ages
    >>> ages(np.array([[9.0, -1.0]]), 10, 0.01).tolist()
    [[0.01, inf]]
    """
    return np.where(sent_tick >= 0, (step - sent_tick) * dt_s, np.inf)


def message_bytes() -> int:
    """Size of the progress broadcast on the wire [bytes]: the team's ``State``
    message (:mod:`firefleet.net.messages`), header included.

    Examples
    --------
    >>> from firefleet.sim.link import message_bytes
    >>> message_bytes()
    81
    """
    state = State(
        run_id=0,
        robot=0,
        tick=0,
        t_s=0.0,
        pose=(0.0, 0.0, 0.0),
        wheel_speed_rad_s=(0.0, 0.0),
        segment=0,
        fraction=0.0,
        arrived=False,
    )
    return encoded_size(state)


@dataclass(frozen=True)
class LinkParams:
    """A radio link's constants.

    Attributes
    ----------
    rate_bit_s : float
        Channel bit rate [bit/s] (inf: no airtime).
    framing_bytes : int
        The radio's bytes around the message (PHY and MAC) [bytes].
    frame_gap_s : float
        Mean idle time between two frames on the channel [s].
    delay_s, jitter_s : float
        Latency after the airtime [s] and its Gaussian deviation [s].
    loss : float
        Mean loss ratio of the channel's loss process, in [0, 1).
    burst_length : float
        Mean loss burst [frames]; 1: independent losses.
    range_m : float
        Hard range; the mean received power meets the sensitivity there [m] (inf: none).
    exponent : float
        Path-loss exponent n.
    shadowing_db : float
        Log-normal shadowing deviation [dB].
    wall_db : float
        Attenuation of one occupied map cell [dB].
    queue_frames : int
        Each sender's queue [frames].
    period_s : float or None
        Broadcast period [s] (None: every tick).
    timeout_s : float
        Age beyond which a value is stale [s].

    Examples
    --------
    >>> from firefleet.sim.link import PRESETS
    >>> xbee = PRESETS["xbee"]
    >>> xbee.rate_bit_s, round(xbee.range_m, 1), round(xbee.airtime_s(81) * 1e3, 3)
    (250000.0, 54.1, 3.136)
    """

    rate_bit_s: float = math.inf
    framing_bytes: int = 0
    frame_gap_s: float = 0.0
    delay_s: float = 0.0
    jitter_s: float = 0.0
    loss: float = 0.0
    burst_length: float = 1.0
    range_m: float = math.inf
    exponent: float = 3.0
    shadowing_db: float = 0.0
    wall_db: float = 6.0
    queue_frames: int = 4
    period_s: float | None = None
    timeout_s: float = 1.0

    def airtime_s(self, message_bytes: int) -> float:
        """Airtime of one frame carrying ``message_bytes`` [s]: ``8 (bytes + framing) /
        rate``."""
        return 8.0 * (message_bytes + self.framing_bytes) / self.rate_bit_s


def _budget_range_m(tx_dbm: float, sensitivity_dbm: float) -> float:
    """Range of a link budget, log-distance with n = 3 from 40 dB at 1 m [m]."""
    return float(10.0 ** ((tx_dbm - sensitivity_dbm - 40.0) / 30.0))


_SHADOW_DB = 4.0
_PERIOD_S = 0.05
"""The radios' default broadcast period [s] (20 Hz: a 250 kbit/s channel carries some
200 broadcasts a second, so a team of ten fills half of it)."""
PRESETS: Mapping[str, LinkParams] = {
    "ideal": LinkParams(),
    "xbee": LinkParams(
        rate_bit_s=250e3,
        framing_bytes=17,
        frame_gap_s=1.76e-3,
        delay_s=0.010,
        range_m=_budget_range_m(0.0, -92.0),
        shadowing_db=_SHADOW_DB,
        period_s=_PERIOD_S,
    ),
    "zigbee": LinkParams(
        rate_bit_s=250e3,
        framing_bytes=33,
        frame_gap_s=1.76e-3,
        delay_s=0.015,
        range_m=_budget_range_m(5.0, -100.0),
        shadowing_db=_SHADOW_DB,
        period_s=_PERIOD_S,
    ),
    "nrf24": LinkParams(
        rate_bit_s=250e3,
        framing_bytes=9,
        frame_gap_s=130e-6,
        delay_s=0.001,
        range_m=_budget_range_m(0.0, -94.0),
        shadowing_db=_SHADOW_DB,
        period_s=_PERIOD_S,
    ),
    "wifi": LinkParams(
        rate_bit_s=54e6,
        framing_bytes=64 + 135,  # headers, and the 20 us preamble as bytes at 54 Mbit/s
        frame_gap_s=96e-6,
        delay_s=0.002,
        range_m=_budget_range_m(14.0, -72.0),
        shadowing_db=_SHADOW_DB,
        period_s=_PERIOD_S,
    ),
}
"""The radios of the deliverable, from their data sheets (module notes)."""


def link_params(spec: LinkSpec) -> LinkParams:
    """The preset of ``spec`` with its overrides.

    Examples
    --------
    >>> from firefleet.scenarios._network import LinkSpec
    >>> from firefleet.sim.link import link_params
    >>> p = link_params(LinkSpec(preset="xbee", loss=0.1, burst_length=3, range_m=60))
    >>> p.rate_bit_s, p.loss, p.burst_length, p.range_m, p.delay_s
    (250000.0, 0.1, 3.0, 60.0, 0.01)
    """
    base = PRESETS[spec.preset]
    over: dict[str, Any] = {"timeout_s": spec.timeout_s}
    for key, name in (
        ("loss", "loss"),
        ("burst_length", "burst_length"),
        ("delay_s", "delay_s"),
        ("jitter_s", "jitter_s"),
        ("range_m", "range_m"),
        ("rate_bit_s", "rate_bit_s"),
        ("period_s", "period_s"),
        ("shadowing_db", "shadowing_db"),
    ):
        value = getattr(spec, key)
        if value is not None:
            over[name] = value
    params = dataclasses.replace(base, **over)
    if params.burst_length > 1.0 and params.loss > 0:
        p = params.loss / (params.burst_length * (1.0 - params.loss))
        if p > 1.0:
            raise InputError(
                f"link.burst_length = {params.burst_length} is too short for link.loss = "
                f"{params.loss}: bursts must average at least loss / (1 - loss) = "
                f"{params.loss / (1.0 - params.loss):.3g} messages"
            )
    return params


def packet_error_rate(
    d_m: FloatArray, range_m: float, exponent: float, shadowing_db: float, walls_db: float = 0.0
) -> FloatArray:
    """Packet error rate against distance (module notes), the range model alone.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.link import packet_error_rate
    >>> packet_error_rate(np.array([10.0, 54.0, 55.0]), 54.0, 3.0, 4.0).round(4).tolist()
    [0.0, 0.5, 1.0]
    """
    d = np.asarray(d_m, dtype=np.float64)
    margin = 10.0 * exponent * np.log10(range_m / np.maximum(d, 1e-9)) - walls_db
    per = (
        0.5 * erfc(margin / (shadowing_db * math.sqrt(2.0)))
        if shadowing_db > 0
        else (np.where(margin > 0, 0.0, 1.0))
    )
    return np.asarray(np.where(d > range_m, 1.0, per), dtype=np.float64)


def wall_cells(grid: OccupancyGrid, xy_m: FloatArray) -> FloatArray:
    """How many occupied cells the straight line between each pair of points crosses.

    Parameters
    ----------
    grid : OccupancyGrid
    xy_m : ndarray, shape (N, 2)
        Positions [m].

    Returns
    -------
    ndarray, shape (N, N)
        Occupied cells along each segment (sampled every half cell; a cell counted once
        however many samples fall in it).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> occ = np.zeros((1, 10), dtype=bool)
    >>> occ[0, 4:6] = True  # a wall two cells thick
    >>> grid = OccupancyGrid(occ, ~occ, resolution_m=1.0)
    >>> wall_cells(grid, np.array([[0.5, 0.5], [9.5, 0.5], [2.5, 0.5]])).tolist()
    [[0.0, 2.0, 0.0], [2.0, 0.0, 2.0], [0.0, 2.0, 0.0]]
    """
    xy = np.asarray(xy_m, dtype=np.float64)[:, :2]
    d = np.hypot(*(xy[None, :, :] - xy[:, None, :]).transpose(2, 0, 1))
    steps = max(2, int(np.ceil(d.max() / (0.5 * grid.resolution_m))) + 1)
    s = np.linspace(0.0, 1.0, steps)
    pts = xy[:, None, None, :] + s[None, None, :, None] * (
        xy[None, :, None, :] - xy[:, None, None, :]
    )
    cells = grid.cell_of(pts)  # (N, N, S, 2)
    occ = grid.occupied_at(pts) & grid.contains(pts)
    new = np.ones(occ.shape, dtype=bool)
    new[..., 1:] = np.any(cells[..., 1:, :] != cells[..., :-1, :], axis=-1)
    return np.asarray((occ & new).sum(axis=-1), dtype=np.float64)


@dataclass
class LinkState:
    """The link's memory (mutable arrays the compiled tick updates in place)."""

    n: int
    keys: tuple[str, ...]
    queue_tick: IntArray
    queue_val: FloatArray
    queue_len: IntArray
    channel: FloatArray
    bad: IntArray
    flight_t: FloatArray
    flight_i: IntArray
    flight_val: FloatArray
    n_flight: IntArray
    held_val: FloatArray
    held_tick: FloatArray
    counters: FloatArray
    rng: np.random.Generator
    dt_s: float


@dataclass(frozen=True)
class LinkModel:
    """The link stage of the world loop (module notes).

    Attributes
    ----------
    params : LinkParams
    seed : int
        Seeds the link's own generator (the loop's other draws stay as they are).
    grid : OccupancyGrid, optional
        A map whose occupied cells attenuate (None: open space).
    message_bytes : int
        Size of a broadcast on the wire [bytes] (:func:`message_bytes`).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.link import LinkModel, LinkParams, ages
    >>> link = LinkModel(LinkParams(delay_s=0.025))
    >>> state = link.init(2, 0.01)
    >>> pose = np.zeros((2, 3))
    >>> sent = {"zeta": np.array([1.0, 2.0])}
    >>> for k in range(1, 5):  # sent at tick 0 only
    ...     inbox, state = link.exchange(state, sent if k == 1 else {}, k * 0.01, pose)
    ...     age = ages(inbox["sent_tick"], k, 0.01)
    ...     print(k, inbox["zeta"][1].tolist(), age[1].round(3).tolist())
    1 [nan, 2.0] [inf, 0.01]
    2 [nan, 2.0] [inf, 0.02]
    3 [1.0, 2.0] [0.03, 0.03]
    4 [1.0, 2.0] [0.04, 0.04]
    """

    params: LinkParams
    seed: int = 0
    grid: OccupancyGrid | None = None
    message_bytes: int = dataclasses.field(default_factory=message_bytes)

    @classmethod
    def from_spec(
        cls, spec: LinkSpec | None, *, seed: int = 0, grid: OccupancyGrid | None = None
    ) -> LinkModel:
        """The model of a scenario's ``link`` key (None: the ideal preset)."""
        return cls(link_params(spec if spec is not None else LinkSpec()), seed=seed, grid=grid)

    def init(self, n_robots: int, dt_s: float) -> LinkState:
        """The link before the first tick: empty queues, nothing held, all pairs good."""
        q = self.params.queue_frames
        cap = max(64, 4 * n_robots)
        return LinkState(
            n=n_robots,
            keys=(),
            queue_tick=np.zeros((n_robots, q), dtype=np.int64),
            queue_val=np.zeros((n_robots, q, 0)),
            queue_len=np.zeros(n_robots, dtype=np.int64),
            channel=np.zeros(1),
            bad=np.zeros((n_robots, n_robots), dtype=np.int64),
            flight_t=np.zeros(cap),
            flight_i=np.zeros((cap, 3), dtype=np.int64),
            flight_val=np.zeros((cap, 0)),
            n_flight=np.zeros(1, dtype=np.int64),
            held_val=np.full((n_robots, n_robots, 0), np.nan),
            held_tick=np.full((n_robots, n_robots), -1.0),
            counters=np.zeros(4),
            rng=np.random.default_rng([self.seed, 0x11A4]),
            dt_s=dt_s,
        )

    def _params_array(self) -> FloatArray:
        p = self.params
        return np.array(
            [
                self.airtime_s,
                p.frame_gap_s,
                p.delay_s,
                p.jitter_s,
                p.loss,
                p.burst_length,
                p.range_m,
                p.exponent,
                p.shadowing_db,
                p.wall_db,
                float(p.queue_frames),
            ]
        )

    @property
    def airtime_s(self) -> float:
        """Airtime of one broadcast [s] (0 at an infinite rate)."""
        return self.params.airtime_s(self.message_bytes)

    def exchange(
        self, state: LinkState, sent: Mapping[str, FloatArray], t_s: float, pose: FloatArray
    ) -> tuple[dict[str, FloatArray], LinkState]:
        """Tick ``k`` (``t_s = k dt``): carry what was sent at ``k - 1``, and return
        what each receiver holds now (module notes)."""
        n = state.n
        dt = state.dt_s
        k = round(t_s / dt)
        if sent and not state.keys:
            self._start(state, tuple(sent))
        m = len(state.keys)
        if sent and tuple(sent) != state.keys:
            raise InputError(
                f"link: the team's messages changed from {state.keys} to {tuple(sent)}"
            )
        payload = np.zeros((n, m))
        send = np.zeros(n, dtype=np.int64)
        if sent:
            for c, key in enumerate(state.keys):
                payload[:, c] = np.asarray(sent[key], dtype=np.float64).reshape(n)
            period = self.params.period_s
            every = 1 if period is None else max(1, round(period / dt))
            if (k - 1) % every == 0:
                send[:] = 1
        queued = int(state.queue_len.sum() + send.sum())
        slot = self.airtime_s + self.params.frame_gap_s
        frames = queued if slot <= 0 else min(queued, math.ceil((dt + slot) / slot) + 1)
        self._reserve(state, frames * max(n - 1, 0))
        rng = state.rng
        order = rng.permutation(n)
        uniform = rng.random((frames, n, 1)) if frames else np.zeros((0, n, 1))
        normal = rng.standard_normal((frames, n, 2)) if frames else np.zeros((0, n, 2))
        walls = (
            wall_cells(self.grid, pose[:, :2])
            if self.grid is not None and frames
            else np.zeros((1, 1))
        )
        if m:
            link_tick(
                k,
                dt,
                self._params_array(),
                payload,
                send,
                np.ascontiguousarray(pose),
                walls,
                order,
                uniform,
                normal,
                state.queue_tick,
                state.queue_val,
                state.queue_len,
                state.channel,
                state.bad,
                state.flight_t,
                state.flight_i,
                state.flight_val,
                state.n_flight,
                state.held_val,
                state.held_tick,
                state.counters,
            )
        inbox = {key: state.held_val[:, :, c] for c, key in enumerate(state.keys)}
        inbox["sent_tick"] = state.held_tick
        return inbox, state

    def _start(self, state: LinkState, keys: tuple[str, ...]) -> None:
        """Size the value arrays for the keys the team broadcasts."""
        n, m, q = state.n, len(keys), self.params.queue_frames
        state.keys = keys
        state.queue_val = np.zeros((n, q, m))
        state.flight_val = np.zeros((state.flight_t.size, m))
        state.held_val = np.full((n, n, m), np.nan)

    def _reserve(self, state: LinkState, more: int) -> None:
        """Grow the in-flight arrays to take ``more`` frames."""
        need = int(state.n_flight[0]) + more
        if need <= state.flight_t.size:
            return
        cap = max(need, 2 * state.flight_t.size)
        used = int(state.n_flight[0])
        for name in ("flight_t", "flight_i", "flight_val"):
            old = getattr(state, name)
            new = np.zeros((cap, *old.shape[1:]), dtype=old.dtype)
            new[:used] = old[:used]
            setattr(state, name, new)

    def counters(self, state: LinkState) -> dict[str, float]:
        """Cumulative ``messages_sent`` and ``messages_lost`` (per directed pair),
        ``queue_drops`` (broadcasts a full queue refused), ``frames`` (on the air)."""
        c = state.counters
        return {
            "messages_sent": float(c[0]),
            "messages_lost": float(c[1]),
            "queue_drops": float(c[2]),
            "frames": float(c[3]),
        }
