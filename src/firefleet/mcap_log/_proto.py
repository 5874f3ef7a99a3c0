"""Just enough of protobuf's wire format to read the Foxglove messages firefleet writes.

Reference: https://protobuf.dev/programming-guides/encoding/ (varints, tags
``field << 3 | wire type``; 0 varint, 1 fixed 64-bit, 2 length-delimited, 5 fixed
32-bit). proto3 leaves out fields at their default (0.0 for a double).
"""

from __future__ import annotations

import struct

__all__ = ["double", "fields", "message"]

Fields = dict[int, list[int | bytes]]


def _varint(data: bytes, i: int) -> tuple[int, int]:
    value = shift = 0
    while True:
        byte = data[i]
        i += 1
        value |= (byte & 0x7F) << shift
        if byte < 0x80:
            return value, i
        shift += 7


def fields(data: bytes) -> Fields:
    """Field number -> values (ints for varints and fixed widths, bytes for the rest).

    Examples
    --------
    >>> from firefleet.mcap_log._proto import fields
    >>> fields(bytes([0x08, 0x96, 0x01, 0x12, 0x02, 0x68, 0x69]))  # 1: 150, 2: "hi"
    {1: [150], 2: [b'hi']}
    """
    out: Fields = {}
    i = 0
    while i < len(data):
        tag, i = _varint(data, i)
        number, wire = tag >> 3, tag & 7
        value: int | bytes
        if wire == 0:
            value, i = _varint(data, i)
        elif wire == 1:
            value, i = int.from_bytes(data[i : i + 8], "little"), i + 8
        elif wire == 2:
            size, i = _varint(data, i)
            value, i = data[i : i + size], i + size
        elif wire == 5:
            value, i = int.from_bytes(data[i : i + 4], "little"), i + 4
        else:
            raise ValueError(f"protobuf wire type {wire} is not read here")
        out.setdefault(number, []).append(value)
    return out


def message(found: Fields, number: int) -> Fields:
    """The sub-message of field ``number`` (empty if absent)."""
    raw = found.get(number, [b""])[-1]
    return fields(raw if isinstance(raw, bytes) else b"")


def double(found: Fields, number: int) -> float:
    """The double of field ``number`` (0.0 if absent, as proto3 writes it)."""
    raw = found.get(number, [0])[-1]
    return (
        float(struct.unpack("<d", int(raw).to_bytes(8, "little"))[0])
        if isinstance(raw, int)
        else 0.0
    )
