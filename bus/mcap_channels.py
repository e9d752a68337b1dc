"""The schemas and channels of one MCAP file, each registered the first time a message needs it:
the one bookkeeping of the show's recorder (``bus.recorder``) and a job's replay
(``scene.replay``), and the already-encoded messages they add beside the bus's own."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from mcap.writer import Writer


@dataclass(frozen=True)
class DerivedMessage:
    """A message the recording adds beside the bus's own, already encoded: a view of the show
    in another schema (Foxglove's scene, ``scene.show_scene``), on its own topic."""

    topic: str
    schema_name: str
    """e.g. ``foxglove.SceneUpdate``."""
    schema_encoding: str
    """``protobuf`` (a FileDescriptorSet) or ``jsonschema``."""
    schema_data: bytes
    message_encoding: str
    """``protobuf`` or ``json``."""
    payload: bytes


class McapChannels:
    """One channel per topic and one schema per name on ``writer`` (a new file: a new one)."""

    def __init__(self, writer: Writer) -> None:
        self.writer = writer
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}

    def channel_id(
        self,
        topic: str,
        *,
        schema_name: str,
        schema_encoding: str,
        schema_data: Callable[[], bytes],
        message_encoding: str,
    ) -> int:
        """``topic``'s channel, registered (with its schema, unless known) on first use;
        ``schema_data`` is only called then."""
        channel_id = self._channels.get(topic)
        if channel_id is None:
            schema_id = self._schemas.get(schema_name)
            if schema_id is None:
                schema_id = self.writer.register_schema(
                    name=schema_name, encoding=schema_encoding, data=schema_data()
                )
                self._schemas[schema_name] = schema_id
            channel_id = self.writer.register_channel(
                topic=topic, message_encoding=message_encoding, schema_id=schema_id
            )
            self._channels[topic] = channel_id
        return channel_id

    def add(self, message: DerivedMessage, stamp_ns: int, sequence: int) -> None:
        """Write ``message`` on its topic, logged and published at ``stamp_ns`` in [ns]."""
        channel_id = self.channel_id(
            message.topic,
            schema_name=message.schema_name,
            schema_encoding=message.schema_encoding,
            schema_data=lambda: message.schema_data,
            message_encoding=message.message_encoding,
        )
        self.writer.add_message(channel_id, stamp_ns, message.payload, stamp_ns, sequence)
