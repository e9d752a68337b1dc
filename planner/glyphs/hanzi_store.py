"""Indexed store of Chinese stroke medians: a small index, one record per character read on demand.

Layout (little-endian), written by :func:`encode_store` and read by :class:`HanziStore`:

- header: ``MAGIC`` (8 bytes), uint32 format version, uint32 character count ``N``, uint32
  metadata length ``M``;
- metadata: ``M`` bytes of UTF-8 JSON (source, grid, y range);
- index: ``N`` uint32 code points in ascending order, then ``N + 1`` uint32 record offsets
  counted from the first record byte (record ``k`` spans ``offsets[k]:offsets[k + 1]``);
- records: per character, unsigned LEB128 varints: the stroke count ``S``, ``S`` point counts,
  then the zigzag-encoded integer steps ``dx0 dy0 dx1 dy1 ...`` of all strokes in order, each
  point relative to the previous point of the same character (the first relative to (0, 0)).

Opening reads the header and index (about 80 kB for 9,574 characters); a character costs one
seek and one read of its record (about 200 bytes).
"""

from __future__ import annotations

import bisect
import json
import struct
import sys
from array import array
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from planner.errors import PlannerError

MAGIC = b"SKQHANZI"
FORMAT_VERSION = 2
_HEADER = struct.Struct("<8sIII")

Point = tuple[int, int]
Strokes = list[list[Point]]


def encode_store(chars: Mapping[str, Sequence[Sequence[Point]]], meta: Mapping[str, Any]) -> bytes:
    """The store's bytes for ``chars`` (character -> strokes of integer points); deterministic."""
    ordered = sorted(chars, key=ord)
    records = bytearray()
    offsets = [0]
    for char in ordered:
        records += _encode_record(chars[char])
        offsets.append(len(records))
    meta_bytes = json.dumps(dict(meta), ensure_ascii=False, sort_keys=True).encode("utf-8")
    return b"".join(
        [
            _HEADER.pack(MAGIC, FORMAT_VERSION, len(ordered), len(meta_bytes)),
            meta_bytes,
            struct.pack(f"<{len(ordered)}I", *(ord(c) for c in ordered)),
            struct.pack(f"<{len(offsets)}I", *offsets),
            bytes(records),
        ]
    )


def _encode_record(strokes: Sequence[Sequence[Point]]) -> bytes:
    values = [len(strokes), *(len(points) for points in strokes)]
    prev_x, prev_y = 0, 0
    for points in strokes:
        for x, y in points:
            values += [_zigzag(x - prev_x), _zigzag(y - prev_y)]
            prev_x, prev_y = x, y
    out = bytearray()
    for value in values:
        while value >= 0x80:
            out.append((value & 0x7F) | 0x80)
            value >>= 7
        out.append(value)
    return bytes(out)


def _zigzag(value: int) -> int:
    return 2 * value if value >= 0 else -2 * value - 1


def _unzigzag(value: int) -> int:
    return value >> 1 if value % 2 == 0 else -((value + 1) >> 1)


def _varints(data: bytes) -> list[int]:
    values: list[int] = []
    value = shift = 0
    for byte in data:
        value |= (byte & 0x7F) << shift
        if byte & 0x80:
            shift += 7
        else:
            values.append(value)
            value = shift = 0
    if shift:
        raise ValueError("record ends inside a number")
    return values


def decode_record(data: bytes) -> Strokes:
    """Strokes of one record as absolute integer points; ValueError when malformed."""
    values = _varints(data)
    if not values or values[0] < 1 or len(values) < 1 + values[0]:
        raise ValueError("bad stroke count")
    counts = values[1 : 1 + values[0]]
    steps = values[1 + values[0] :]
    if any(n < 1 for n in counts) or len(steps) != 2 * sum(counts):
        raise ValueError("point counts do not match the steps")
    strokes: Strokes = []
    x = y = k = 0
    for n in counts:
        points = []
        for _ in range(n):
            x += _unzigzag(steps[k])
            y += _unzigzag(steps[k + 1])
            k += 2
            points.append((x, y))
        strokes.append(points)
    return strokes


class HanziStore:
    """Read-only view of a store file: the index in memory, records read per character."""

    def __init__(self, path: Path) -> None:
        """Read the header and index of ``path``; PlannerError naming the file when malformed."""
        self.path = path
        try:
            with path.open("rb") as f:
                magic, version, count, meta_len = _HEADER.unpack(f.read(_HEADER.size))
                if magic != MAGIC or version != FORMAT_VERSION:
                    raise ValueError(f"not a version {FORMAT_VERSION} hanzi store")
                self.meta: dict[str, Any] = json.loads(f.read(meta_len).decode("utf-8"))
                self._codepoints = _uint32s(f.read(4 * count), count)
                self._offsets = _uint32s(f.read(4 * (count + 1)), count + 1)
            self._records_at = _HEADER.size + meta_len + 4 * (2 * count + 1)
        except (OSError, ValueError, struct.error) as exc:
            raise PlannerError(f"{path.name}: cannot read the stroke store: {exc}") from exc

    def __len__(self) -> int:
        return len(self._codepoints)

    def __contains__(self, char: object) -> bool:
        return isinstance(char, str) and len(char) == 1 and self._find(char) is not None

    def characters(self) -> frozenset[str]:
        """Every character in the store."""
        return frozenset(map(chr, self._codepoints))

    def strokes(self, char: str) -> Strokes | None:
        """Strokes of ``char`` as absolute integer points, or None when it is not in the store."""
        k = self._find(char)
        if k is None:
            return None
        start, end = self._offsets[k], self._offsets[k + 1]
        try:
            with self.path.open("rb") as f:
                f.seek(self._records_at + start)
                data = f.read(end - start)
            if len(data) != end - start:
                raise ValueError("file is truncated")
            return decode_record(data)
        except (OSError, ValueError) as exc:
            where = f"{self.path.name}: record of {char!r} (U+{ord(char):04X})"
            raise PlannerError(f"{where}: {exc}") from exc

    def _find(self, char: str) -> int | None:
        code = ord(char)
        k = bisect.bisect_left(self._codepoints, code)
        if k < len(self._codepoints) and self._codepoints[k] == code:
            return k
        return None


def _uint32s(data: bytes, count: int) -> array[int]:
    if len(data) != 4 * count:
        raise ValueError("index is truncated")
    values = array("I")  # 4 bytes on every platform CPython supports
    values.frombytes(data)
    if sys.byteorder == "big":
        values.byteswap()
    return values
