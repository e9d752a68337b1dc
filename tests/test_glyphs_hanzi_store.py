"""The indexed stroke store: lossless round trip, per-character reads, clear errors on bad files."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.errors import PlannerError
from planner.glyphs.hanzi import STORE_PATH, hanzi_strokes_em
from planner.glyphs.hanzi_store import HanziStore, decode_record, encode_store

_points = st.lists(
    st.tuples(st.integers(-5000, 5000), st.integers(-5000, 5000)), min_size=1, max_size=12
)
_chars = st.dictionaries(
    st.characters(min_codepoint=0x20, max_codepoint=0x10FFFF, categories=("L", "N", "P", "S")),
    st.lists(_points, min_size=1, max_size=6),
    min_size=1,
    max_size=8,
)


@settings(max_examples=50, deadline=None)
@given(_chars)
def test_round_trip_is_lossless(
    tmp_path_factory: pytest.TempPathFactory, chars: dict[str, list[list[tuple[int, int]]]]
) -> None:
    path = tmp_path_factory.mktemp("store") / "s.bin"
    path.write_bytes(encode_store(chars, {"grid": 1024}))
    store = HanziStore(path)
    assert store.characters() == frozenset(chars)
    assert store.meta == {"grid": 1024}
    for char, strokes in chars.items():
        assert store.strokes(char) == [list(points) for points in strokes]
    assert store.strokes("\x00") is None and "\x00" not in store


def test_encoding_is_deterministic_and_order_free() -> None:
    a = {"十": [[(0, 0), (10, 0)], [(5, 5), (5, -5)]], "一": [[(0, 0), (9, 1)]]}
    b = dict(reversed(list(a.items())))
    assert encode_store(a, {"x": 1}) == encode_store(b, {"x": 1})


def test_small_steps_take_one_byte() -> None:
    # stroke count, point count, then four steps in -64..63: six bytes
    assert decode_record(bytes([1, 2, 2 * 3, 2 * 60, 2 * 5 - 1, 0])) == [[(3, 60), (-2, 60)]]


def test_committed_store_known_character() -> None:
    store = HanziStore(STORE_PATH)
    assert len(store) == 9574
    yong = store.strokes("永")
    assert yong is not None and len(yong) == 5
    assert all(0 <= x <= 1024 and -124 <= y <= 900 for s in yong for x, y in s)
    assert len(hanzi_strokes_em("永")) == 5


def test_bad_magic_names_the_file(tmp_path: Path) -> None:
    path = tmp_path / "bad.bin"
    path.write_bytes(b"NOTHANZI" + bytes(12))
    with pytest.raises(PlannerError, match=r"bad\.bin: cannot read the stroke store"):
        HanziStore(path)


def test_truncated_record_names_the_character(tmp_path: Path) -> None:
    path = tmp_path / "cut.bin"
    path.write_bytes(encode_store({"永": [[(0, 0), (500, 700)]]}, {})[:-1])
    with pytest.raises(PlannerError, match=r"cut\.bin: record of '永' \(U\+6C38\): file is trunc"):
        HanziStore(path).strokes("永")


def test_malformed_record_is_refused() -> None:
    with pytest.raises(ValueError, match="ends inside a number"):
        decode_record(bytes([1, 0x80]))
    with pytest.raises(ValueError, match="do not match"):
        decode_record(bytes([1, 2, 0, 0]))
