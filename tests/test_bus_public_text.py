"""Public text is plain text (issue 30): a submission's ``client_id``, its strokes document's
``label`` and ``device`` and its typed ``text`` are checked when the request is decoded, so no
escape, bidirectional override or markup from the public reaches the orchestrator."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bus.codec import MessageError, decode
from bus.keys import ShowKeys
from bus.messages import SubmitReply, SubmitRequest
from bus.public_text import MAX_CLIENT_ID_CHARS, MAX_LABEL_CHARS
from bus.rpc import NoReplyError, RemoteError, query_one, serve
from bus.session import Session, loopback_settings, open_session
from cli.main import main as skyquill

KEYS = ShowKeys("public-text-test")
SOLO = Path(__file__).resolve().parents[1] / "shows" / "solo.yaml"
DRAWING = {"units": "px", "y_axis": "down", "strokes": [[[0, 0], [10, 10]]]}
ESCAPES = "\x1b[2J\x1b]8;;http://e.vil\x07"
MARKUP = "[blink]x[/]"
BIDI = "\u202eevil\u2066"
UNSAFE = re.compile(r"[\x00-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069\u200e\u200f\u2028\u2029]")


def _payload(**fields: Any) -> bytes:
    return json.dumps(fields).encode()


def _refusal(session: Session, payload: bytes) -> RemoteError:
    """The submit queryable's refusal of ``payload``. A query sent before the router has learnt
    of a queryable declared a moment ago gets no reply at all (a fresh clone's CI run lost the
    first one so): sent again until one comes, within 20 s."""
    deadline = time.monotonic() + 20.0
    while True:
        try:
            query_one(session, KEYS.submit, payload, SubmitReply, timeout_s=5.0)
        except RemoteError as exc:
            return exc
        except NoReplyError:
            assert time.monotonic() < deadline, "the submit queryable never answered"
            continue
        raise AssertionError(f"accepted: {payload!r}")


@pytest.mark.timeout(60)
def test_escapes_and_markup_over_the_bus_never_reach_the_orchestrator() -> None:
    hostile = [
        (_payload(strokes={**DRAWING, "label": ESCAPES + MARKUP}), "$.strokes.label"),
        (_payload(strokes={**DRAWING, "label": MARKUP}), "$.strokes.label"),
        (_payload(strokes={**DRAWING, "device": BIDI}), "$.strokes.device"),
        (_payload(text="A", client_id=MARKUP + ESCAPES), "$.client_id"),
        (_payload(text="A", client_id="c" + BIDI), "$.client_id"),
        (_payload(text="A\x1b[2J"), "$.text"),
        (_payload(strokes={**DRAWING, "label": "x" * (MAX_LABEL_CHARS + 1)}), "$.strokes.label"),
        (_payload(text="A", client_id="c" * (MAX_CLIENT_ID_CHARS + 1)), "$.client_id"),
    ]
    received: list[SubmitRequest] = []

    def on_submit(request: SubmitRequest) -> SubmitReply:
        received.append(request)
        return SubmitReply(ok=True, job_id=f"j{len(received)}", state="queued")

    bus = loopback_settings()
    with (
        open_session(bus, role="router"),
        open_session(bus, role="client") as orchestrator,
        open_session(bus, role="client") as submitter,
    ):
        serve(orchestrator, KEYS.submit, SubmitRequest, on_submit)
        for payload, field in hostile:
            refused = _refusal(submitter, payload)
            assert (refused.info.code, refused.info.field) == ("invalid", field)
            assert not UNSAFE.search(refused.info.message)  # the answer echoes none
        plain = _payload(strokes={**DRAWING, "label": "tick (v2)"}, client_id="booth-3")
        assert query_one(submitter, KEYS.submit, plain, SubmitReply, timeout_s=5.0).ok
        typed = SubmitRequest(text="[b]x", client_id="cli")  # brackets are written, not markup
        assert query_one(submitter, KEYS.submit, typed, SubmitReply, timeout_s=5.0).ok
    assert [(r.client_id, r.text) for r in received] == [("booth-3", None), ("cli", "[b]x")]


def _clean_name(value: str) -> bool:
    return not UNSAFE.search(value) and not re.search(r"\[[^\[\]]*\]", value)


hostile_text = st.one_of(
    st.text(max_size=120),
    st.text(st.sampled_from(list("[]/@#ab \x1b\x07\x9b\x7f\u202e\u2066\u200e\u2028")), max_size=40),
)


@settings(max_examples=300, deadline=None)
@given(hostile_text, hostile_text)
def test_any_text_is_refused_or_decodes_plain(name: str, typed: str) -> None:
    """Whatever a submitter puts in a name or a text (lone surrogates, C1 controls, isolates,
    markup, long strings), the decoded request holds plain text or is refused as such."""
    for raw in (
        _payload(strokes={**DRAWING, "label": name, "device": name}, client_id=name),
        _payload(text=typed or "A", client_id="c"),
    ):
        try:
            request = decode(raw, SubmitRequest)
        except MessageError as exc:
            assert exc.info.code in ("invalid", "bad_json"), exc.info
            continue
        assert request.strokes is None or _clean_name(request.strokes["label"])
        assert _clean_name(request.client_id) and len(request.client_id) <= MAX_CLIENT_ID_CHARS
        assert request.text is None or not UNSAFE.search(request.text)


plain_names = st.text(
    st.characters(exclude_categories=("Cc", "Cf", "Cs", "Zl", "Zp"), exclude_characters="[]"),
    max_size=MAX_CLIENT_ID_CHARS,
)


@settings(max_examples=200, deadline=None)
@given(plain_names)
def test_plain_text_passes_unchanged(name: str) -> None:
    raw = _payload(strokes={**DRAWING, "label": name}, client_id=name)
    request = decode(raw, SubmitRequest)
    assert request.client_id == name and request.strokes is not None
    assert request.strokes["label"] == name


@pytest.mark.parametrize(
    ("client_id", "said"),
    [(f"a{ESCAPES}", "client_id holds U+001B"), ("c" * (MAX_CLIENT_ID_CHARS + 1), "<= 100")],
)
def test_the_submit_command_refuses_a_client_id_the_bus_would_in_one_line(
    capsys: pytest.CaptureFixture[str], client_id: str, said: str
) -> None:
    """Checked before any session opens (no router here): one line, no traceback."""
    assert skyquill(["submit", str(SOLO), "--text", "A", "--client-id", client_id]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and said in err and "\x1b" not in err, err
