"""A running show served live to Foxglove over its WebSocket protocol (``foxglove-sdk``).

:class:`LiveView` takes every sample of the show's bus (a read-only watcher's subscription),
turns it into the scene's messages (:class:`scene.show_scene.ShowScene`) and logs them on the
SDK's channels, one per topic; the SDK's server sends each message to the viewers subscribed to
its channel. The venue is sent every :data:`LIVE_VENUE_PERIOD_S`, so a viewer who connects late
sees it at once. The view is its own process: viewers cost the show only this one subscriber,
whatever their number.

Every channel is opened when the view is made, before its server starts
(:func:`scene.show_scene.scene_channels`), never as its first message comes. When a channel
opens while a viewer is connected, the SDK's server sends that viewer the advertisement before
it records the channel as advertised to it (``ConnectedClient::advertise_channels``), so a
viewer that subscribes as soon as it reads the advertisement, as Foxglove does, can be refused
("Unknown channel ID") and never get the channel: about 1 viewer in 20 on a loaded machine
(foxglove-sdk 0.30.3). The channels open before a viewer connects are advertised to it, and
recorded, before the server reads anything from it.

Zenoh calls :meth:`LiveView.on_sample` on its own threads, and they must never wait on a viewer:
a sample of the scene (telemetry, an event) only goes into a bounded queue there, and the view's
own thread decodes it, draws it and logs it. When that thread falls behind (a slow viewer, a
busy machine) and :data:`LIVE_QUEUE_SAMPLES` wait, the oldest is dropped and counted in
:attr:`LiveView.dropped`: telemetry is state, and the newest sample is the one worth drawing.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Iterable
from types import TracebackType

import foxglove
import msgspec

from bus.keys import ShowKeys
from bus.mcap_channels import DerivedMessage
from bus.messages import Event, Telemetry
from bus.recorder import message_type_for_topic
from scene.show_scene import ShowScene, scene_channels
from showfile import Show

LIVE_VENUE_PERIOD_S = 1.0
"""The venue and vehicle models are sent this often in the live view, in [s]."""
LIVE_QUEUE_SAMPLES = 2_000
"""Samples waiting for the view's thread at most; past it the oldest goes (5 s of telemetry of
20 vehicles at 20 Hz)."""
_DRAWN = (Telemetry, Event)
"""The message types the scene draws; other samples never enter the queue."""

log = logging.getLogger(__name__)


class LiveView:
    """The scene of one show logged to a Foxglove context, on a thread of its own; use as a
    context manager (the thread ends on exit)."""

    def __init__(
        self, show: Show, context: foxglove.Context, *, max_queued: int = LIVE_QUEUE_SAMPLES
    ) -> None:
        self.scene = ShowScene(show, venue_period_s=LIVE_VENUE_PERIOD_S)
        self.context = context
        self.keys = ShowKeys(show.show_id)
        self.max_queued = max_queued
        self._channels: dict[str, foxglove.Channel] = {}
        for channel in scene_channels():  # all of them, before any viewer connects
            self._channel(channel)
        self._queue: deque[tuple[str, type[msgspec.Struct], bytes, int]] = deque()
        self._wake = threading.Condition()
        self._fixed_due = False
        self._closed = False
        self.samples = 0
        """Bus samples the scene draws taken so far (queued)."""
        self.dropped = 0
        """Samples dropped unseen: the oldest, while :data:`LIVE_QUEUE_SAMPLES` waited."""
        self.drawn = 0
        """Samples drawn and logged so far (by the view's thread)."""
        self.failures = 0
        """Samples that could not be drawn (e.g. not of their topic's type; logged once)."""
        self._thread = threading.Thread(target=self._run, name="scene-live", daemon=True)
        self._thread.start()

    def on_sample(self, key: str, payload: bytes) -> None:
        """One bus sample (Zenoh's threads): queued if the scene draws it; returns at once."""
        message_type = message_type_for_topic(self.keys, key)
        if message_type not in _DRAWN:
            return
        assert message_type is not None
        item = (key, message_type, payload, time.time_ns())
        with self._wake:  # held for an append: never while anything is drawn or sent
            self.samples += 1
            if len(self._queue) >= self.max_queued:
                self._queue.popleft()
                self.dropped += 1
            self._queue.append(item)
            self._wake.notify()

    def send_fixed(self) -> None:
        """The venue and vehicle models, sent by the view's thread next, whatever the bus says
        (a viewer of a quiet show, or of one whose bus this view cannot hear, sees the venue)."""
        with self._wake:
            self._fixed_due = True
            self._wake.notify()

    def close(self) -> None:
        """Stop the view's thread (what waits is dropped)."""
        with self._wake:
            self._closed = True
            self._wake.notify()
        self._thread.join()

    def __enter__(self) -> LiveView:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def _run(self) -> None:
        while True:
            with self._wake:
                while not (self._queue or self._fixed_due or self._closed):
                    self._wake.wait()
                if self._closed:
                    return
                fixed, self._fixed_due = self._fixed_due, False
                item = self._queue.popleft() if self._queue else None
            if fixed:
                stamp_ns = time.time_ns()
                self._log(self.scene.fixed(stamp_ns, force=True), stamp_ns)
            if item is not None:
                self._draw(*item)

    def _draw(
        self, key: str, message_type: type[msgspec.Struct], payload: bytes, stamp_ns: int
    ) -> None:
        try:
            message = msgspec.json.decode(payload, type=message_type)
            self._log(self.scene.derive(key, message, stamp_ns), stamp_ns)
        except Exception:  # one sample that cannot be drawn never stops the view
            if not self.failures:
                log.exception("a sample on %s could not be drawn (logged once)", key)
            self.failures += 1
            return
        self.drawn += 1

    def _log(self, messages: Iterable[DerivedMessage], stamp_ns: int) -> None:
        for message in messages:
            self._channel(message).log(message.payload, log_time=stamp_ns)

    def _channel(self, message: DerivedMessage) -> foxglove.Channel:
        """``message``'s channel: one of those opened with the view (a topic the scene does not
        declare would open here, late, see the module's docstring)."""
        channel = self._channels.get(message.topic)
        if channel is None:
            schema = foxglove.Schema(
                name=message.schema_name,
                encoding=message.schema_encoding,
                data=message.schema_data,
            )
            channel = foxglove.Channel(
                message.topic,
                schema=schema,
                message_encoding=message.message_encoding,
                context=self.context,
            )
            self._channels[message.topic] = channel
        return channel
