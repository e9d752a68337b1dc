"""Seeded malformed payloads for tests/test_bus_fuzz.py: valid-looking JSON with mutations
(unknown fields, missing fields, wrong types, huge and non-finite numbers, overlong strings, deep
nesting, invalid UTF-8, out-of-range stroke coordinates), byte-level damage, random bytes, deep
bracket runs and a few payloads over the size limit."""

from __future__ import annotations

import json
import random
from typing import Any


class Fuzzer:
    """Seeded payloads; placeholders in the JSON become raw bytes after serialisation."""

    def __init__(self, seed: int) -> None:
        self.rng = random.Random(seed)
        self.raw: dict[str, bytes] = {}

    def _raw(self, data: bytes) -> str:
        token = f"@@raw{len(self.raw)}@@"
        self.raw[token] = data
        return token

    def value(self) -> Any:
        r = self.rng
        return r.choice(
            [
                None,
                True,
                r.randint(-5, 5),
                r.random(),
                "",
                "x" * r.choice([1, 129, 1001, 20_000]),
                [1, "a"],
                {"a": 1},
                10 ** r.choice([19, 40, 400, 4000]),
                r.choice([1e308, -1e308, 5e-324, float("nan"), float("inf"), -float("inf")]),
                self._raw(r.choice([b"\xff", b"\xc3", b"\xed\xa0\x80", b'"\\ud800"'])),
                self._raw(self.deep()),
            ]
        )

    def deep(self) -> bytes:
        depth = self.rng.choices([33, 100, 1000, 5000, 100_000], [30, 30, 30, 10, 1])[0]
        opener, closer = self.rng.choice([(b"[", b"]"), (b'{"a":', b"}")])
        return opener * depth + (closer * depth if self.rng.random() < 0.7 else b"")

    def mutate(self, obj: dict[str, Any]) -> None:
        r = self.rng
        keys = list(obj)
        kind = r.randrange(6)
        if kind == 0:
            obj[r.choice(["colour", "v2", "", "jobs", "x" * 300])] = self.value()
        elif kind == 1 and keys:
            del obj[r.choice(keys)]
        elif kind == 2 and keys:
            obj[r.choice(keys)] = self.value()
        elif kind == 3 and isinstance(obj.get("strokes"), dict):
            bad = r.choice([1e308, -2e6, 10**400, float("nan"), "1", None, [1, 2, 3, 4, 5]])
            obj["strokes"] = {**obj["strokes"], "strokes": [[[0, 0], [bad, 1]], [[1, 1], [2, 2]]]}
        elif kind == 4 and isinstance(obj.get("job"), dict):
            self.mutate(obj["job"])
        else:
            obj[r.choice(keys or ["v"])] = self._raw(self.deep())

    def encode(self, obj: Any) -> bytes:
        data = json.dumps(obj, ensure_ascii=False).encode("utf-8", "surrogatepass")
        for token, raw in self.raw.items():
            data = data.replace(f'"{token}"'.encode(), raw)
        self.raw.clear()
        return data

    def payload(self, templates: list[dict[str, Any]]) -> bytes | None:
        r = self.rng
        kind = r.random()
        if kind < 0.65:
            obj = json.loads(json.dumps(r.choice(templates)))
            for _ in range(r.randint(1, 3)):
                self.mutate(obj)
            return self.encode(obj)
        if kind < 0.85:
            data = bytearray(self.encode(r.choice(templates)))
            for _ in range(r.randint(1, 4)):
                at = r.randrange(len(data) + 1)
                choice = r.randrange(3)
                if choice == 0:
                    del data[at:]
                elif choice == 1:
                    data[at:at] = bytes([r.randrange(256)])
                elif at < len(data):
                    data[at] = r.randrange(256)
            return bytes(data)
        if kind < 0.93:
            return r.randbytes(r.randrange(0, 300))
        if kind < 0.97:
            return self.deep()
        if kind < 0.999:
            return self.encode(self.value())
        return b'{"text": "' + b"x" * 1_100_000 + b'"}'
