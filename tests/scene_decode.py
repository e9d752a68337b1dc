"""Decoding recorded Foxglove channels with the schema each channel carries (protobuf
FileDescriptorSet or JSON schema), independently of the code that wrote them."""

from __future__ import annotations

import json
from typing import Any

import jsonschema
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory


def protobuf_class(schema_name: str, schema_data: bytes) -> Any:
    """The message class named ``schema_name`` built from a serialized FileDescriptorSet."""
    files = descriptor_pb2.FileDescriptorSet.FromString(schema_data)
    pool = descriptor_pool.DescriptorPool()
    pending = list(files.file)
    while pending:  # add files after those they depend on
        added = False
        for proto in list(pending):
            try:
                pool.Add(proto)
            except TypeError:
                continue
            pending.remove(proto)
            added = True
        assert added, f"unresolvable files in the schema of {schema_name}"
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema_name))


def decoded(encoding: str, schema_name: str, schema_data: bytes, payload: bytes) -> Any:
    """A recorded message checked against its channel's schema: a protobuf message, or the JSON
    value (validated with ``jsonschema``)."""
    if encoding == "protobuf":
        message = protobuf_class(schema_name, schema_data)()
        message.ParseFromString(payload)
        assert message.SerializeToString() == payload or message.ByteSize() == len(payload)
        return message
    assert encoding == "json", encoding
    value = json.loads(payload)
    jsonschema.validate(value, json.loads(schema_data))
    return value
