"""Pure checks of what the public sends: size, shape, counts and the text blocklist.

Nothing here does I/O; :mod:`kiosk.app` reads the body (capped) and hands the bytes over.
"""

from __future__ import annotations

import json
import re
import unicodedata
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from bus.public_text import drawing_label
from kiosk import wording
from kiosk.errors import RejectedError

_SURROGATE_ESCAPE = re.compile(rb"\\u[dD][89a-fA-F]")
"""A ``\\ud800``-``\\udfff`` escape: half of a surrogate pair, or a lone surrogate."""
FORWARDED_STROKES_FIELDS = ("strokes", "units", "y_axis", "canvas")
"""What the kiosk passes on of a drawing: its geometry. A ``label`` or ``device`` the page never
sets would reach the operator's screens as free text that the blocklist never saw."""


@dataclass(frozen=True)
class SubmissionLimits:
    """Bounds on one submission (from the show file's ``kiosk`` section)."""

    max_payload_bytes: int = 250_000
    """Largest request body in bytes."""
    max_strokes: int = 60
    """Most strokes in one drawing."""
    max_points: int = 5_000
    """Most points in one drawing, all strokes together."""
    max_text_chars: int = 1
    """Longest typed text in characters (1: a single character; more: a short word)."""
    blocklist: tuple[str, ...] = ()
    """Words (any script) that typed text may not contain, compared after normalisation."""
    max_phrase_chars: int = 0
    """Longest phrase written together, one character per board: the show's boards in a row
    (below 2: the show takes no phrase)."""


@dataclass(frozen=True)
class Submission:
    """A checked submission: exactly one of ``text`` and ``strokes``."""

    text: str | None
    """Typed text, NFC-normalised and stripped."""
    strokes: dict[str, Any] | None
    """The strokes document as sent, only its ``FORWARDED_STROKES_FIELDS`` (docs/formats.md)."""
    label: str = field(default="")
    """A short description for people: the text, or ``drawing (N strokes)``."""
    phrase: bool = False
    """``text`` is a phrase: one character per board, written together
    (``orchestrator/phrases.py``)."""

    @property
    def characters(self) -> int:
        """How many characters it asks the drones to write (a phrase counts as its
        characters in the per-address limit)."""
        return len(self.text or "") if self.phrase else 1


def normalise_for_blocklist(text: str) -> str:
    """Compatibility-folded, case-folded text without spaces or punctuation, for matching."""
    folded = unicodedata.normalize("NFKC", text).casefold()
    return "".join(ch for ch in folded if unicodedata.category(ch)[0] in "LN")


def is_blocked(text: str, blocklist: Sequence[str]) -> bool:
    """True when ``text`` contains any blocklisted word (after :func:`normalise_for_blocklist`)."""
    folded = normalise_for_blocklist(text)
    return any(word and word in folded for word in map(normalise_for_blocklist, blocklist))


def decode_json_body(raw: bytes) -> Mapping[str, Any]:
    """The JSON object in ``raw``, or a :class:`RejectedError` (``bad_json``), lone surrogates
    (``"\\ud800"``, which no UTF-8 text can hold) included."""
    try:
        data = json.loads(raw.decode("utf-8"))
        if _SURROGATE_ESCAPE.search(raw):  # pairs make one character; a lone half cannot encode
            json.dumps(data, ensure_ascii=False).encode("utf-8")
    except (ValueError, RecursionError):  # not UTF-8, not JSON, a 5000-digit integer
        raise RejectedError("bad_json", wording.BAD_JSON) from None
    if not isinstance(data, dict):
        raise RejectedError("bad_json", wording.BAD_JSON)
    return data


def check_submission(
    data: Mapping[str, Any],
    limits: SubmissionLimits,
    has_glyph: Callable[[str], bool],
) -> Submission:
    """Validate a decoded body ``{"text": ...}``, ``{"text": ..., "phrase": true}`` or
    ``{"strokes": {...}}``."""
    unknown = set(data) - {"text", "strokes", "phrase"}
    if unknown or not isinstance(data.get("phrase", False), bool):
        raise RejectedError("bad_request", wording.BAD_JSON)
    text, strokes = data.get("text"), data.get("strokes")
    if text is not None and strokes is not None:
        raise RejectedError("bad_request", wording.BAD_REQUEST)
    if data.get("phrase", False):
        if strokes is not None:
            raise RejectedError("bad_request", wording.BAD_REQUEST)
        return _check_phrase(text, limits, has_glyph)
    if text is not None:
        return _check_text(text, limits, has_glyph)
    if strokes is not None:
        return _check_strokes(strokes, limits)
    raise RejectedError("empty", wording.NOTHING)


def _check_text(
    text: Any, limits: SubmissionLimits, has_glyph: Callable[[str], bool]
) -> Submission:
    if not isinstance(text, str):
        raise RejectedError("bad_request", wording.BAD_JSON)
    text = " ".join(unicodedata.normalize("NFC", text).split())
    if not text:
        raise RejectedError("empty", wording.TEXT_EMPTY)
    if len(text) > limits.max_text_chars:
        limit = limits.max_text_chars
        message = wording.TEXT_ONE_CHAR if limit == 1 else wording.TEXT_TOO_LONG.format(limit=limit)
        raise RejectedError("text_too_long", message)
    if is_blocked(text, limits.blocklist):
        raise RejectedError("blocked_text", wording.BLOCKED)
    for ch in text:
        if ch != " " and not has_glyph(ch):
            raise RejectedError("no_glyph", wording.NO_GLYPH.format(char=ch), status=422)
    return Submission(text=text, strokes=None, label=text)


def _check_phrase(
    text: Any, limits: SubmissionLimits, has_glyph: Callable[[str], bool]
) -> Submission:
    """A phrase: 2 to ``max_phrase_chars`` characters without spaces, each one a drone writes
    on its own board (the orchestrator checks the same, ``orchestrator/submissions.py``)."""
    if text is not None and not isinstance(text, str):
        raise RejectedError("bad_request", wording.BAD_JSON)
    limit = limits.max_phrase_chars
    if limit < 2:
        raise RejectedError("no_phrase", wording.NO_PHRASE)
    text = unicodedata.normalize("NFC", text or "").strip()
    if not text:
        raise RejectedError("empty", wording.TEXT_EMPTY)
    if any(ch.isspace() for ch in text):
        raise RejectedError("phrase_spaces", wording.PHRASE_SPACES)
    if len(text) < 2:
        raise RejectedError("phrase_too_short", wording.PHRASE_TOO_SHORT)
    if len(text) > limit:
        raise RejectedError("phrase_too_long", wording.PHRASE_TOO_LONG.format(limit=limit))
    if is_blocked(text, limits.blocklist):
        raise RejectedError("blocked_text", wording.BLOCKED)
    for ch in text:
        if not has_glyph(ch):
            raise RejectedError("no_glyph", wording.NO_GLYPH.format(char=ch), status=422)
    return Submission(text=text, strokes=None, label=text, phrase=True)


def _check_strokes(doc: Any, limits: SubmissionLimits) -> Submission:
    if not isinstance(doc, dict) or not isinstance(doc.get("strokes"), list):
        raise RejectedError("bad_request", wording.BAD_JSON)
    strokes: list[Any] = doc["strokes"]
    if not strokes:
        raise RejectedError("empty", wording.NOTHING)
    if len(strokes) > limits.max_strokes:
        raise RejectedError(
            "too_many_strokes", wording.TOO_MANY_STROKES.format(limit=limits.max_strokes)
        )
    total = 0
    for i, stroke in enumerate(strokes):
        if not isinstance(stroke, list):
            raise RejectedError("bad_request", wording.BAD_DRAWING, stroke_index=i)
        total += len(stroke)
        if total > limits.max_points:
            raise RejectedError("too_many_points", wording.TOO_MANY_POINTS, stroke_index=i)
        if len(stroke) < 2:
            raise RejectedError("short_stroke", wording.SHORT_STROKE, stroke_index=i)
    label = drawing_label(len(strokes))
    drawn = {key: doc[key] for key in FORWARDED_STROKES_FIELDS if key in doc}
    return Submission(text=None, strokes=drawn, label=label)
