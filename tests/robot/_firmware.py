"""The sketch's C logic (firmware/arduino/firefleet_motor/ff_*.c) compiled on the host
with gcc and loaded with ctypes, for the tests that hold Python and firmware to one
protocol and one controller."""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

FIRMWARE = Path(__file__).resolve().parents[2] / "firmware" / "arduino" / "firefleet_motor"

MAX_PAYLOAD = 32


class PidGains(ctypes.Structure):
    _fields_ = [(name, ctypes.c_float) for name in ("kp", "ki", "kd", "tf", "b", "tt", "limit")]


class Pid(ctypes.Structure):
    _fields_ = [(name, ctypes.c_float) for name in ("integral", "derivative", "last")]


class Motor(ctypes.Structure):
    _fields_ = [
        ("gains", PidGains),
        ("pid", Pid * 2),
        ("counts_per_rad", ctypes.c_float),
        ("supply_v", ctypes.c_float),
        ("history", (ctypes.c_int32 * 2) * 3),
        ("filled", ctypes.c_uint8),
        ("ref_rad_s", ctypes.c_float * 2),
        ("duty", ctypes.c_float * 2),
        ("mode", ctypes.c_uint8),
        ("flags", ctypes.c_uint8),
        ("estop_latched", ctypes.c_uint8),
        ("last_command_us", ctypes.c_uint32),
    ]


class Decoder(ctypes.Structure):
    _fields_ = [
        ("buf", ctypes.c_uint8 * (MAX_PAYLOAD + 6)),
        ("len", ctypes.c_uint8),
        ("crc_errors", ctypes.c_uint16),
        ("framing_errors", ctypes.c_uint16),
    ]


def build(tmp: Path) -> ctypes.CDLL:
    """Compile the firmware's portable C into a shared library; gcc is required (it is
    on every machine that builds Python packages), so its absence fails the test."""
    cc = shutil.which("gcc") or shutil.which("cc")
    assert cc is not None, "the firmware tests need a C compiler (gcc): apt-get install gcc"
    lib = tmp / "libff.so"
    sources = [str(FIRMWARE / "ff_protocol.c"), str(FIRMWARE / "ff_motor.c")]
    subprocess.run(
        [
            cc,
            "-std=c99",
            "-O2",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-shared",
            "-fPIC",
            "-o",
            str(lib),
            *sources,
        ],
        check=True,
    )
    dll = ctypes.CDLL(str(lib))
    u8p = ctypes.POINTER(ctypes.c_uint8)
    dll.ff_crc16.restype = ctypes.c_uint16
    dll.ff_crc16.argtypes = [u8p, ctypes.c_size_t]
    dll.ff_encode.restype = ctypes.c_size_t
    dll.ff_encode.argtypes = [ctypes.c_uint8, u8p, ctypes.c_uint8, u8p]
    dll.ff_decoder_feed.argtypes = [ctypes.POINTER(Decoder), ctypes.c_uint8, u8p, u8p, u8p]
    dll.ff_decoder_poll.argtypes = [ctypes.POINTER(Decoder), u8p, u8p, u8p]
    dll.ff_pid_step.restype = ctypes.c_float
    dll.ff_pid_step.argtypes = [
        ctypes.POINTER(Pid),
        ctypes.POINTER(PidGains),
        ctypes.c_float,
        ctypes.c_float,
        ctypes.c_float,
    ]
    dll.ff_motor_init.argtypes = [
        ctypes.POINTER(Motor),
        ctypes.POINTER(PidGains),
        ctypes.c_float,
        ctypes.c_float,
        ctypes.c_uint32,
    ]
    dll.ff_motor_command.argtypes = [
        ctypes.POINTER(Motor),
        ctypes.c_uint8,
        u8p,
        ctypes.c_uint8,
        ctypes.c_uint32,
    ]
    dll.ff_motor_tick.argtypes = [
        ctypes.POINTER(Motor),
        ctypes.c_uint32,
        ctypes.POINTER(ctypes.c_int32),
        ctypes.POINTER(ctypes.c_float),
    ]
    return dll


def buffer(data: bytes) -> ctypes.Array[ctypes.c_uint8]:
    """A C copy of ``data`` (at least one byte long)."""
    return (ctypes.c_uint8 * max(1, len(data))).from_buffer_copy(data or b"\0")


def c_encode(dll: ctypes.CDLL, kind: int, payload: bytes) -> bytes:
    out = (ctypes.c_uint8 * (MAX_PAYLOAD + 6))()
    n = dll.ff_encode(kind, buffer(payload), len(payload), out)
    return bytes(out[:n])


def c_decode(dll: ctypes.CDLL, stream: bytes) -> tuple[list[tuple[int, bytes]], int, int]:
    """Frames, CRC errors and framing errors of the C decoder fed byte by byte."""
    dec = Decoder()
    kind, n = ctypes.c_uint8(), ctypes.c_uint8()
    payload = (ctypes.c_uint8 * MAX_PAYLOAD)()
    frames = []
    for byte in stream:
        got = dll.ff_decoder_feed(
            ctypes.byref(dec), byte, ctypes.byref(kind), payload, ctypes.byref(n)
        )
        while got:
            frames.append((kind.value, bytes(payload[: n.value])))
            got = dll.ff_decoder_poll(
                ctypes.byref(dec), ctypes.byref(kind), payload, ctypes.byref(n)
            )
    return frames, dec.crc_errors, dec.framing_errors
