"""The wire contract: key expressions, versioned JSON messages, Zenoh sessions, asyncio bridge.

The only package that imports ``zenoh``.

- ``bus.keys``: every key expression (:class:`~bus.keys.ShowKeys`).
- ``bus.messages``: every message (msgspec structs).
- ``bus.codec``: ``encode``/``decode``, the payload checks made before parsing, ``MessageError``.
- ``bus.session``: ``open_session(settings, role=...)``, the one way to open a session.
- ``bus.bridge``: Zenoh threads -> asyncio channels (drop-oldest ring, FIFO, latest-by-key).
- ``bus.pubsub``: typed publish/subscribe, liveliness tokens and watchers.
- ``bus.rpc``: typed queries (``query``/``aquery``) and queryables (``serve``/``serve_async``).
- ``bus.recorder``: MCAP recording of a show's key space with JSON schemas.
"""
