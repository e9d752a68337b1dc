"""The wire contract: key expressions, versioned JSON messages, Zenoh sessions, asyncio bridge.

The only package that imports ``zenoh``.
"""
