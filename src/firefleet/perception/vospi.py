"""FLIR Lepton VoSPI (video over SPI) stream: packets, segments, frames.

Written to the FLIR Lepton Engineering Datasheet (document 500-0659-00-09, rev 203),
section 4.2.2 (Lepton 2.x, 80 x 60) and 4.2.3 (Lepton 3.x, 160 x 120), Raw14 video
format with telemetry disabled (the camera's defaults):

* A packet is 164 bytes: a 2-byte ID, a 2-byte CRC and a 160-byte payload, every field
  big-endian (MSB first). The payload is one video line of 80 16-bit pixels.
* ID ``xFxx`` (low nibble of the first byte all ones) marks a *discard* packet, sent
  when no video is ready; it carries no data and is skipped.
* Otherwise the low 12 bits of the ID are the packet number. On a Lepton 3, bits 12-14
  of packet 20's ID are the segment number ``TTT`` (1 to 4; 0 marks an invalid
  segment); in every other packet those bits are ignored. The top bit is zero.
* The CRC is CRC-16-CCITT (polynomial ``x^16 + x^12 + x^5 + 1``, seed 0, no final
  XOR) of the whole packet, computed with the ID's four most significant bits and the
  CRC field set to zero.
* Lepton 2: a frame is 60 packets numbered 0 to 59, packet ``p`` is row ``p``.
* Lepton 3: a segment is 60 packets (30 rows, two packets per 160-pixel row: packet
  ``p`` is row ``p // 2``, columns ``80 (p % 2)`` to ``80 (p % 2) + 79`` of the
  segment), a frame is segments 1, 2, 3, 4 in that order; the camera sends each unique
  frame followed by two invalid ones (segment numbers 1, 2, 3, 4, 0 x 8, 1, ...).

:func:`parse_vospi` reads a captured byte stream and never raises on damage: a packet
whose CRC fails, a packet out of sequence, an unexpected segment number or a truncated
tail is dropped and counted in :class:`VospiStats`, and the parser re-synchronises on
the next packet whose CRC holds (byte by byte, so a stream that lost or gained bytes
is recovered too). A frame is emitted only from a complete, CRC-valid run: 60 packets
in order per segment, segments 1-2-3-4 in order with nothing between them but discard
packets. Any damage between two segments abandons the partial frame, so segments of
different frames are never put together.

Limits of the protocol, not of the parser: packets and segments carry no frame
identifier, so the loss of exactly a whole number of frame cycles of video packets (60
packets on a Lepton 2; 4 segments, or 12 with the camera's invalid frames, on a
Lepton 3) leaves a consistent sequence, and the frame around the gap is assembled from
two frames (telemetry's frame counter, not parsed here, would be needed to see it); and
an accidental CRC match among corrupted bytes has probability 2^-16 per packet tried
(reduced further by the sequence checks).
An all-zero packet passes the CRC trivially (CRC of zeros is zero); it is treated as
damage, since no Lepton output (Raw14 or TLinear) is zero across a whole line.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet.errors import InputError

__all__ = [
    "PACKET_BYTES",
    "VospiFrames",
    "VospiStats",
    "crc16_ccitt",
    "encode_vospi",
    "packet_crc",
    "parse_vospi",
]

logger = logging.getLogger(__name__)

PACKET_BYTES = 164
"""Bytes per VoSPI packet in Raw14 mode: 2 ID + 2 CRC + 160 payload."""
PAYLOAD_BYTES = 160
PACKETS_PER_SEGMENT = 60
"""Video packets per Lepton 2 frame, and per Lepton 3 segment (telemetry disabled)."""
SEGMENTS_PER_FRAME = 4
"""Lepton 3: segments per frame."""
SEGMENT_ID_PACKET = 20
"""Lepton 3: the packet whose ID carries the segment number."""
_SCAN_WINDOW = 2048
"""Byte offsets tried at once while re-synchronising."""

Lepton = Literal[2, 3]


def _crc_table() -> NDArray[np.uint16]:
    table = np.zeros(256, dtype=np.uint16)
    for byte in range(256):
        crc = byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
        table[byte] = crc & 0xFFFF
    return table


_CRC_TABLE = _crc_table()
_CRC_TABLE.flags.writeable = False  # a constant of the algorithm, shared read-only


def crc16_ccitt(data: ArrayLike) -> NDArray[np.uint16]:
    """CRC-16-CCITT (polynomial 0x1021, seed 0, no reflection, no final XOR) per row.

    Parameters
    ----------
    data : array_like of uint8, shape (P, L)
        ``P`` byte strings of length ``L`` (batch-first: all rows at once).

    Returns
    -------
    ndarray of uint16, shape (P,)
        The CRC of each row (the "XMODEM" variant; equals ``binascii.crc_hqx(row, 0)``).

    Examples
    --------
    >>> import binascii
    >>> import numpy as np
    >>> from firefleet.perception.vospi import crc16_ccitt
    >>> hex(int(crc16_ccitt(np.frombuffer(b"123456789", np.uint8)[None])[0]))  # XMODEM check
    '0x31c3'
    >>> int(crc16_ccitt([list(b"lepton")])[0]) == binascii.crc_hqx(b"lepton", 0)
    True
    """
    rows = np.asarray(data, dtype=np.uint8)
    if rows.ndim != 2:
        raise InputError(f"data must have shape (P, L), got {rows.shape}")
    crc = np.zeros(rows.shape[0], dtype=np.uint16)
    for column in rows.T:
        crc = (crc << np.uint16(8)) ^ _CRC_TABLE[(crc >> np.uint16(8)) ^ column]
    return crc


def packet_crc(packets: ArrayLike) -> NDArray[np.uint16]:
    """The CRC a VoSPI packet must carry (datasheet 4.2.2.1 / 4.2.3.1).

    Parameters
    ----------
    packets : array_like of uint8, shape (P, 164)
        Whole packets.

    Returns
    -------
    ndarray of uint16, shape (P,)
        CRC-16-CCITT of each packet with the ID's top four bits and the CRC field zeroed.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.vospi import PACKET_BYTES, encode_vospi, packet_crc
    >>> packets = np.frombuffer(encode_vospi(np.zeros((1, 60, 80), np.uint16), lepton=2), np.uint8)
    >>> packets = packets.reshape(-1, PACKET_BYTES)
    >>> carried = packets[:, 2].astype(np.uint16) << 8 | packets[:, 3]
    >>> packets.shape, bool(np.all(packet_crc(packets) == carried))
    ((60, 164), True)
    """
    pk = np.array(packets, dtype=np.uint8, copy=True)
    if pk.ndim != 2 or pk.shape[1] != PACKET_BYTES:
        raise InputError(f"packets must have shape (P, {PACKET_BYTES}), got {pk.shape}")
    pk[:, 0] &= 0x0F
    pk[:, 2:4] = 0
    return crc16_ccitt(pk)


def _stored_crc(packets: NDArray[np.uint8]) -> NDArray[np.uint16]:
    return (packets[:, 2].astype(np.uint16) << np.uint16(8)) | packets[:, 3]


def _is_discard(packets: NDArray[np.uint8]) -> NDArray[np.bool_]:
    return np.asarray((packets[:, 0] & 0x0F) == 0x0F, dtype=np.bool_)


def _is_good_video(packets: NDArray[np.uint8]) -> NDArray[np.bool_]:
    """CRC holds, top bit clear, not a discard, not all zero."""
    ok = packet_crc(packets) == _stored_crc(packets)
    ok &= (packets[:, 0] & 0x80) == 0
    ok &= ~_is_discard(packets)
    ok &= packets.any(axis=1)
    return np.asarray(ok, dtype=np.bool_)


@dataclass(frozen=True)
class VospiStats:
    """What the parser saw, packet by packet.

    Attributes
    ----------
    packets : int
        Whole packets read (video, discard, and damaged ones).
    video_packets : int
        Video packets with a valid CRC.
    discard_packets : int
        Discard packets (ID ``xFxx``), skipped.
    bad_packets : int
        Packets dropped as damaged: CRC failure, all-zero, or top ID bit set; each run
        of unreadable bytes before a re-synchronisation counts once.
    resync_bytes : int
        Bytes skipped while re-synchronising on the next valid packet.
    out_of_sequence : int
        CRC-valid video packets whose number was not the next one expected.
    segments : int
        Complete segments (Lepton 3) or frames (Lepton 2) of 60 packets.
    invalid_segments : int
        Lepton 3 segments numbered 0 (the camera's invalid frames) or above 4.
    frames : int
        Frames emitted.
    frames_dropped : int
        Partial frames abandoned because of damage or a segment out of order.
    trailing_bytes : int
        Bytes at the end, too few for a packet (a truncated stream).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.vospi import encode_vospi, parse_vospi
    >>> stream = encode_vospi(np.ones((2, 60, 80), np.uint16), lepton=2)
    >>> stats = parse_vospi(stream[:-10], lepton=2).stats  # the last packet cut short
    >>> stats.frames, stats.frames_dropped, stats.trailing_bytes
    (1, 1, 154)
    """

    packets: int = 0
    video_packets: int = 0
    discard_packets: int = 0
    bad_packets: int = 0
    resync_bytes: int = 0
    out_of_sequence: int = 0
    segments: int = 0
    invalid_segments: int = 0
    frames: int = 0
    frames_dropped: int = 0
    trailing_bytes: int = 0


@dataclass(frozen=True)
class VospiFrames:
    """Frames assembled from a VoSPI stream.

    Attributes
    ----------
    frames : ndarray of uint16, shape (F, H, W)
        Pixel words as sent (Raw14 counts, or TLinear centikelvin): ``(F, 60, 80)`` for
        a Lepton 2, ``(F, 120, 160)`` for a Lepton 3, in stream order.
    stats : VospiStats
        Counts of everything read and dropped.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.vospi import encode_vospi, parse_vospi
    >>> result = parse_vospi(encode_vospi(np.ones((3, 120, 160), np.uint16), lepton=3))
    >>> result.frames.shape, result.frames.dtype, result.stats.segments
    ((3, 120, 160), dtype('uint16'), 12)
    """

    frames: NDArray[np.uint16] = field(repr=False)
    stats: VospiStats


def _frame_shape(lepton: Lepton) -> tuple[int, int]:
    return (60, 80) if lepton == 2 else (120, 160)


def _check_lepton(lepton: object) -> Lepton:
    if lepton not in (2, 3):
        raise InputError(f"lepton must be 2 or 3, got {lepton!r}")
    return 2 if lepton == 2 else 3


def encode_vospi(
    frames: ArrayLike,
    *,
    lepton: Lepton = 3,
    invalid_frames: int = 0,
    discards_between: int = 0,
) -> bytes:
    """Byte stream that a Lepton sends for ``frames`` (the inverse of :func:`parse_vospi`).

    Parameters
    ----------
    frames : array_like of integers in [0, 65535], shape (F, 60, 80) or (F, 120, 160)
        Pixel words (Raw14 counts or TLinear centikelvin).
    lepton : {2, 3}, keyword-only
        Camera generation: 60 x 80 frames of 60 packets, or 120 x 160 frames of four
        60-packet segments.
    invalid_frames : int, keyword-only
        Lepton 3: invalid frames (four segments numbered 0, copies of the last frame)
        after each unique frame; the camera sends 2 (datasheet 4.2.3.3).
    discards_between : int, keyword-only
        Discard packets after each segment (Lepton 3) or frame (Lepton 2).

    Returns
    -------
    bytes
        The stream, ``164 * packets`` bytes.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.vospi import PACKET_BYTES, encode_vospi
    >>> len(encode_vospi(np.zeros((1, 60, 80), np.uint16), lepton=2)) == 60 * PACKET_BYTES
    True
    >>> len(encode_vospi(np.zeros((1, 120, 160), np.uint16), lepton=3)) == 4 * 60 * PACKET_BYTES
    True
    """
    lep = _check_lepton(lepton)
    rows, cols = _frame_shape(lep)
    raw = np.asarray(frames)
    if raw.ndim != 3 or raw.shape[1:] != (rows, cols):
        raise InputError(f"frames must have shape (F, {rows}, {cols}), got {raw.shape}")
    if not np.issubdtype(raw.dtype, np.integer) or (
        raw.size and (raw.min() < 0 or raw.max() > 0xFFFF)
    ):
        raise InputError("frames must hold integers in [0, 65535]")
    if invalid_frames < 0 or discards_between < 0:
        raise InputError("invalid_frames and discards_between must be >= 0")
    words = raw.astype(">u2")
    discard = np.zeros((discards_between, PACKET_BYTES), dtype=np.uint8)
    discard[:, 0] = 0x0F  # ID xFxx; the rest is don't-care
    discard[:, 1] = 0xFF
    chunks: list[NDArray[np.uint8]] = []
    numbers = np.arange(PACKETS_PER_SEGMENT, dtype=np.uint16)
    for frame in words:
        if lep == 2:
            payloads = [frame.reshape(PACKETS_PER_SEGMENT, cols)]
            segment_ids = [0]
        else:
            quarters = frame.reshape(SEGMENTS_PER_FRAME, PACKETS_PER_SEGMENT, 80)
            payloads = [quarters[s] for s in range(SEGMENTS_PER_FRAME)] * (1 + invalid_frames)
            segment_ids = [1, 2, 3, 4] + [0] * (SEGMENTS_PER_FRAME * invalid_frames)
        for payload, ttt in zip(payloads, segment_ids, strict=True):
            ids = numbers.copy()
            if lep == 3:
                ids[SEGMENT_ID_PACKET] |= np.uint16(ttt << 12)
            pk = np.zeros((PACKETS_PER_SEGMENT, PACKET_BYTES), dtype=np.uint8)
            pk[:, 0] = ids >> 8
            pk[:, 1] = ids & 0xFF
            pk[:, 4:] = payload.view(np.uint8).reshape(PACKETS_PER_SEGMENT, PAYLOAD_BYTES)
            crc = packet_crc(pk)
            pk[:, 2] = crc >> 8
            pk[:, 3] = crc & 0xFF
            chunks.extend((pk, discard))
    if not chunks:
        return b""
    return np.concatenate(chunks).tobytes()


class _Assembler:
    """The packet -> segment -> frame state machine (one stream, one pass)."""

    def __init__(self, lepton: Lepton) -> None:
        self.lepton = lepton
        self.counts = dict.fromkeys(VospiStats.__dataclass_fields__, 0)
        self.segment = np.zeros((PACKETS_PER_SEGMENT, PAYLOAD_BYTES), dtype=np.uint8)
        self.next_packet = 0  # next packet number expected in the current segment
        self.segment_number = 0
        self.parts: list[NDArray[np.uint8]] = []  # Lepton 3: segments 1.. of this frame
        self.frames: list[NDArray[np.uint8]] = []

    def abandon(self) -> None:
        """Damage: drop the segment in progress and the partial frame."""
        if self.parts or self.next_packet > 0:
            self.counts["frames_dropped"] += 1
        self.next_packet = 0
        self.parts = []

    def video(self, packet: NDArray[np.uint8]) -> None:
        number = ((int(packet[0]) & 0x0F) << 8) | int(packet[1])
        self.counts["video_packets"] += 1
        if number != self.next_packet:
            self.counts["out_of_sequence"] += 1
            self.abandon()
            if number != 0:
                return
        if self.lepton == 3 and number == SEGMENT_ID_PACKET:
            self.segment_number = (int(packet[0]) >> 4) & 0x07
        self.segment[number] = packet[4:]
        self.next_packet = number + 1
        if self.next_packet == PACKETS_PER_SEGMENT:
            self.next_packet = 0
            self.counts["segments"] += 1
            self.complete_segment()

    def complete_segment(self) -> None:
        data = self.segment.copy()
        if self.lepton == 2:
            self.emit([data])
            return
        ttt = self.segment_number
        if ttt == 0 or ttt > SEGMENTS_PER_FRAME:
            self.counts["invalid_segments"] += 1
            if self.parts:
                self.counts["frames_dropped"] += 1
            self.parts = []
        elif ttt == len(self.parts) + 1:
            self.parts.append(data)
            if ttt == SEGMENTS_PER_FRAME:
                self.emit(self.parts)
                self.parts = []
        else:
            self.counts["frames_dropped"] += 1
            self.parts = [data] if ttt == 1 else []

    def emit(self, segments: list[NDArray[np.uint8]]) -> None:
        self.frames.append(np.concatenate(segments))
        self.counts["frames"] += 1


def _next_good_offset(buf: NDArray[np.uint8], start: int) -> int:
    """First offset >= ``start`` where a good video packet begins (``len(buf)`` if none)."""
    n = buf.size
    lanes = np.arange(PACKET_BYTES)
    while start + PACKET_BYTES <= n:
        stop = min(start + _SCAN_WINDOW, n - PACKET_BYTES + 1)
        offsets = np.arange(start, stop)
        good = _is_good_video(buf[offsets[:, None] + lanes])
        if good.any():
            return int(offsets[int(np.argmax(good))])
        start = stop
    return n


def parse_vospi(data: bytes | bytearray | memoryview, *, lepton: Lepton = 3) -> VospiFrames:
    """Assemble the frames of a captured VoSPI byte stream.

    Parameters
    ----------
    data : bytes-like
        The stream as read from the SPI bus (any length; damage allowed).
    lepton : {2, 3}, keyword-only
        Camera generation (Lepton 2.x: 80 x 60; Lepton 3.x: 160 x 120 in 4 segments).

    Returns
    -------
    VospiFrames
        The frames, ``(F, 60, 80)`` or ``(F, 120, 160)`` uint16, and the counts of
        what was read and dropped.

    Raises
    ------
    InputError
        Only if ``data`` is not bytes-like or ``lepton`` is not 2 or 3. Damage in the
        stream never raises: it is dropped and counted.

    Notes
    -----
    Datasheet 500-0659-00-09 sections 4.2.2-4.2.3. Packets are checked in vectorised
    batches; the state machine then walks the good packets in order.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.vospi import encode_vospi, parse_vospi
    >>> frames = np.random.default_rng(0).integers(0, 16384, (2, 60, 80))
    >>> result = parse_vospi(encode_vospi(frames, lepton=2), lepton=2)
    >>> bool(np.array_equal(result.frames, frames)), result.stats.frames, result.stats.bad_packets
    (True, 2, 0)
    """
    lep = _check_lepton(lepton)
    if not isinstance(data, bytes | bytearray | memoryview):
        raise InputError(f"VoSPI data must be bytes, got {type(data).__name__}")
    buf = np.frombuffer(bytes(data), dtype=np.uint8)
    n = buf.size
    asm = _Assembler(lep)
    counts = asm.counts
    pos = 0
    batch = 4 * SEGMENTS_PER_FRAME * PACKETS_PER_SEGMENT
    while pos + PACKET_BYTES <= n:
        k = min((n - pos) // PACKET_BYTES, batch)
        packets = buf[pos : pos + k * PACKET_BYTES].reshape(k, PACKET_BYTES)
        discard = _is_discard(packets)
        ok = discard | _is_good_video(packets)
        run = k if ok.all() else int(np.argmin(ok))
        for i in range(run):
            if discard[i]:
                counts["discard_packets"] += 1
            else:
                asm.video(packets[i])
        counts["packets"] += run
        pos += run * PACKET_BYTES
        if run < k:  # damage at pos: drop it and find the next good packet
            counts["bad_packets"] += 1
            counts["packets"] += 1
            asm.abandon()
            nxt = _next_good_offset(buf, pos + 1)
            counts["resync_bytes"] += nxt - pos
            pos = nxt
    tail = n - pos
    if tail:
        counts["trailing_bytes"] = tail
        asm.abandon()
    elif asm.parts or asm.next_packet:
        counts["frames_dropped"] += 1  # the stream ended inside a frame
    rows, cols = _frame_shape(lep)
    if asm.frames:
        frames = np.stack(asm.frames).view(">u2").reshape(-1, rows, cols).astype(np.uint16)
    else:
        frames = np.zeros((0, rows, cols), dtype=np.uint16)
    stats = VospiStats(**counts)
    if stats.bad_packets or stats.out_of_sequence or stats.frames_dropped:
        logger.info("VoSPI stream damaged: %s", stats)
    return VospiFrames(frames=frames, stats=stats)
