"""What an agent and its planning worker say to each other over the worker's stdin and stdout.

Frames: a 4-byte big-endian length, then a pickle (both ends are this program, parent and child;
nothing from the network is unpickled: assignments arrive as validated bus messages first).

Requests, one at a time, each answered by one reply:

- ``("init", show, vehicle_id, time_scale)``: the vehicle whose jobs follow (first request);
- ``("warm",)``: plan a small character as a job is planned, answer None (the modules and
  caches of planning loaded before the first job);
- ``("prepare", assignment)`` -> a :class:`PreparedJob` whose ``context`` is a
  :class:`SealedContext` (the kind's plan, pickled: the agent never needs its classes);
- ``("measure", prepared, trace)`` -> :class:`JobMetrics`;
- ``("archive", prepared, trace, metrics)`` -> the job's directory as a string;
- ``("close",)``: wait for a picture still being drawn, answer None, exit.

Replies: ``("ok", value, cpu_s)`` with the worker's CPU time of the request in [s], or
``("error", ErrorInfo)``.
"""

from __future__ import annotations

import pickle
import struct
from dataclasses import dataclass
from typing import BinaryIO

HEADER = struct.Struct(">I")
"""A frame's length prefix."""
MAX_FRAME_BYTES = 256 * 1024 * 1024
"""Largest frame either end accepts (a flown trace is about 1 MB a minute)."""


class FrameError(EOFError):
    """The other end closed the pipe or sent something that is not a frame."""


@dataclass(frozen=True)
class SealedContext:
    """A prepared job's context (the kind's ``WritingPlan``) pickled by the worker; opened again
    only there, to measure and record the flown job."""

    blob: bytes
    """The pickle."""


def frame(message: object) -> bytes:
    """The bytes of one frame holding ``message``."""
    body = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    return HEADER.pack(len(body)) + body


def body_length(header: bytes) -> int:
    """The body length a frame header announces (FrameError if absent or implausible)."""
    if len(header) != HEADER.size:
        raise FrameError("the pipe closed")
    (length,) = HEADER.unpack(header)
    if length > MAX_FRAME_BYTES:
        raise FrameError(f"a frame of {length} bytes is over the limit")
    return int(length)


def unframe(body: bytes) -> object:
    """The message in a frame's body."""
    return pickle.loads(body)


def read_frame(stream: BinaryIO) -> object:
    """The next message on a blocking stream (FrameError at its end)."""
    length = body_length(stream.read(HEADER.size))
    body = stream.read(length)
    if len(body) != length:
        raise FrameError("the pipe closed inside a frame")
    return unframe(body)


def write_frame(stream: BinaryIO, message: object) -> None:
    """Send one message on a blocking stream."""
    stream.write(frame(message))
    stream.flush()
