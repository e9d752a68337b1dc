"""A running show served live to Foxglove over its WebSocket protocol (``foxglove-sdk``).

:class:`LiveView` takes every sample of the show's bus (a read-only watcher's subscription),
turns it into the scene's messages (:class:`scene.show_scene.ShowScene`) and logs them on the
SDK's channels, one per topic, created as they first appear; the SDK's server sends each
message to the viewers subscribed to its channel. The venue is sent every
:data:`LIVE_VENUE_PERIOD_S`, so a viewer who connects late sees it at once. The view is its own
process: viewers cost the show only this one subscriber, whatever their number.
"""

from __future__ import annotations

import threading
import time

import foxglove

from bus.recorder import DerivedMessage
from scene.show_scene import ShowScene
from showfile import Show

LIVE_VENUE_PERIOD_S = 1.0
"""The venue and vehicle models are sent this often in the live view, in [s]."""


class LiveView:
    """The scene of one show logged to a Foxglove context (thread-safe: Zenoh calls
    :meth:`on_sample` from its threads)."""

    def __init__(self, show: Show, context: foxglove.Context) -> None:
        self.scene = ShowScene(show, venue_period_s=LIVE_VENUE_PERIOD_S)
        self.context = context
        self._channels: dict[str, foxglove.Channel] = {}
        self._lock = threading.Lock()
        self.samples = 0
        """Bus samples taken so far."""

    def on_sample(self, key: str, payload: bytes) -> None:
        """One bus sample: its scene messages, logged now."""
        stamp_ns = time.time_ns()
        with self._lock:
            self.samples += 1
            for message in self.scene.derive(key, payload, stamp_ns):
                self._channel(message).log(message.payload, log_time=stamp_ns)

    def send_fixed(self) -> None:
        """The venue and vehicle models now, whatever the bus says (a viewer of a quiet show,
        or of one whose bus this view cannot hear, still sees the venue)."""
        stamp_ns = time.time_ns()
        with self._lock:
            for message in self.scene.fixed(stamp_ns, force=True):
                self._channel(message).log(message.payload, log_time=stamp_ns)

    def _channel(self, message: DerivedMessage) -> foxglove.Channel:
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
