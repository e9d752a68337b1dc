"""Messages to and from JSON bytes: ``encode``, and ``decode`` with the checks made before parsing.

A payload is refused before the parser sees it when it is too large, not UTF-8 or nested too
deep; every failure becomes a :class:`MessageError` carrying an :class:`~bus.messages.ErrorInfo`,
so a service can always answer. A request is held to :func:`request_limit`, a reply or a
publication to :data:`MAX_PAYLOAD_BYTES`. docs/protocol.md lists the limits and codes.
"""

from __future__ import annotations

import functools
import re
from itertools import accumulate
from typing import TYPE_CHECKING, TypeVar

import msgspec

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

from bus.messages import ErrorInfo, VehicleCommand

MAX_PAYLOAD_BYTES = 1_000_000
"""Largest JSON payload of a reply, a publication or an assignment. A snapshot of a 250-vehicle
show needs most: 700 jobs and 250 vehicles with every field at its longest, 540 kB, and the
orchestrator's budgets for strokes and pictures (400 kB) on top."""
MAX_REQUEST_BYTES = 262_144
"""Largest request a queryable accepts, assignments apart (:func:`request_limit`). A character
needs far less: the Chinese character with the longest ink in the glyph store (鬮, 27 strokes)
drawn at the kiosk's spacing on a 400 px pad is 1,378 points, a 36 kB submission (61 kB with
widths); the kiosk's largest drawing (5,000 points, 4-digit coordinates) 139 kB, 229 kB with
widths. Parsing is what a large request costs its service: 1 MB of strokes took 45-60 ms, a
request at this limit 28 ms."""
MAX_DEPTH = 32
"""Deepest nesting of JSON arrays and objects in any payload (a request with a strokes document
needs 5); checked before parsing."""

M = TypeVar("M", bound=msgspec.Struct)

_encoder = msgspec.json.Encoder()


class MessageError(ValueError):
    """A payload that is not a valid message; ``info`` says what and where."""

    def __init__(self, info: ErrorInfo) -> None:
        self.info = info
        super().__init__(info.message)


def encode(message: msgspec.Struct) -> bytes:
    """JSON bytes of a message."""
    return _encoder.encode(message)


_QUOTE, _BACKSLASH = ord('"'), ord("\\")
_STRING_EDGE = re.compile(rb'(?<!\\)(?:\\\\)*"')
"""A quote after an even run of backslashes (with that run): one that opens or closes a string."""
_NOT_BRACKETS = bytes(b for b in range(256) if b not in b"[]{}")
_BRACKET_STEP = tuple(1 if b in b"[{" else -1 if b in b"]}" else 0 for b in range(256))
SCANNED_TOKENS_MAX = 50_000
"""Up to this many brackets and quotes the depth is found with bytes and regex operations (a
snapshot of 500 jobs and 250 vehicles, 24,000 of them: 18 ms, numpy 10 ms once imported);
beyond, vectorised by numpy, imported then (~0.15 s; 1 MB of brackets: numpy 28 ms, 200 ms
without)."""


def nesting_depth(raw: bytes) -> int:
    """Deepest nesting of arrays and objects in JSON text, strings skipped, without parsing.

    Exact for valid JSON, and for invalid JSON up to its first error (as far as a parser goes).
    Linear: 0 (not scanned) when the text has at most :data:`MAX_DEPTH` opening brackets; up to
    :data:`SCANNED_TOKENS_MAX` brackets and quotes, without numpy (a one-off ``skyquill status``
    decodes a busy show's snapshot without loading it); beyond, vectorised.
    """
    if raw.count(b"[") + raw.count(b"{") <= MAX_DEPTH:
        return 0
    if sum(raw.count(token) for token in (b"[", b"]", b"{", b"}", b'"')) <= SCANNED_TOKENS_MAX:
        return _depth_scanned(raw)
    return _depth_vectorised(raw)


def _depth_scanned(raw: bytes) -> int:
    """The depth from the text between strings (every other piece split at string edges)."""
    brackets = b"".join(_STRING_EDGE.split(raw)[0::2]).translate(None, _NOT_BRACKETS)
    return max(0, max(accumulate(map(_BRACKET_STEP.__getitem__, brackets)), default=0))


@functools.cache
def _depth_steps() -> NDArray[np.int32]:
    """+1 for each opening bracket's byte, -1 for each closing one's, 0 otherwise."""
    import numpy as np

    steps = np.zeros(256, dtype=np.int32)
    steps[[ord("["), ord("{")]] = 1
    steps[[ord("]"), ord("}")]] = -1
    return steps


def _depth_vectorised(raw: bytes) -> int:
    import numpy as np

    data = np.frombuffer(raw, dtype=np.uint8)
    steps = _depth_steps()[data]
    if b'"' in raw:
        quote = data == _QUOTE
        if b"\\" in raw:  # a quote after an odd run of backslashes is escaped
            index = np.arange(data.size, dtype=np.int64)
            last_other = np.maximum.accumulate(np.where(data == _BACKSLASH, -1, index))
            quote[1:] &= ((index[:-1] - last_other[:-1]) & 1) == 0
        steps[np.bitwise_xor.accumulate(quote)] = 0  # inside a string (and its closing quote)
    return int(steps.cumsum().max(initial=0))


def _refuse(code: str, message: str, field: str | None = None) -> MessageError:
    return MessageError(ErrorInfo(code=code, message=message, field=field))


def request_limit(request_type: type[msgspec.Struct] | None) -> int:
    """Largest payload of a request of ``request_type`` (None: a key that takes no request).

    An assignment (:class:`~bus.messages.VehicleCommand`, which only the orchestrator may send)
    carries a whole job's strokes as the orchestrator re-encoded them, so it may be a little
    larger than the submission it came from: :data:`MAX_PAYLOAD_BYTES`. Every other request,
    a submission first, :data:`MAX_REQUEST_BYTES`.
    """
    return MAX_PAYLOAD_BYTES if request_type is VehicleCommand else MAX_REQUEST_BYTES


def check_size(size: int, max_bytes: int) -> None:
    """Raise ``too_large`` when a payload of ``size`` bytes exceeds ``max_bytes``."""
    if size > max_bytes:
        raise _refuse("too_large", f"payload of {size} bytes exceeds {max_bytes} bytes")


def _check_raw(raw: bytes, max_bytes: int) -> None:
    check_size(len(raw), max_bytes)
    if not raw.isascii():
        try:
            raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise _refuse("bad_json", f"not UTF-8: {exc.reason} at byte {exc.start}") from None
    if (depth := nesting_depth(raw)) > MAX_DEPTH:
        raise _refuse("too_deep", f"JSON nested {depth} deep; at most {MAX_DEPTH} levels")


@functools.cache
def _decoder(message_type: type[M]) -> msgspec.json.Decoder[M]:
    """One decoder per message type, made once: ``msgspec.json.decode(raw, type=...)`` looks the
    type up on every call (Telemetry, timeit on the shared 2-core machine: 2.8-3.5 us a call
    against 2.6-3.0 us; ``bench_bus``'s intake decodes 1,000 a second at 50 vehicles)."""
    return msgspec.json.Decoder(message_type)


def decode(
    payload: bytes | bytearray | memoryview | str,
    message_type: type[M],
    *,
    max_bytes: int = MAX_PAYLOAD_BYTES,
) -> M:
    """Parse and validate a payload; raises :class:`MessageError` naming the problem.

    Checked before parsing: size (``too_large`` beyond ``max_bytes``), UTF-8 (``bad_json``),
    nesting depth (``too_deep``). Any failure of the parser itself becomes ``bad_json`` too:
    nothing else escapes, so a service can always answer.
    """
    raw = payload.encode("utf-8", "surrogatepass") if isinstance(payload, str) else bytes(payload)
    _check_raw(raw, max_bytes)
    try:
        message: M = _decoder(message_type).decode(raw)
    except msgspec.ValidationError as exc:
        text = str(exc)
        field = text.rsplit("at `", 1)[1].rstrip("`") if "at `" in text else None
        raise _refuse("invalid", text, field) from None
    except msgspec.DecodeError as exc:
        raise _refuse("bad_json", f"not valid JSON: {exc}") from None
    except (ValueError, RecursionError, OverflowError, MemoryError) as exc:
        raise _refuse("bad_json", f"not valid JSON: {type(exc).__name__}: {exc}") from None
    return message
