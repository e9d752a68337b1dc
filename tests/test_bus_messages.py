"""The wire contract: keys are well-formed and payload errors say what and where."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import msgspec
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bus.codec import (
    MAX_DEPTH,
    MAX_PAYLOAD_BYTES,
    MessageError,
    _depth_scanned,
    _depth_vectorised,
    decode,
    encode,
    nesting_depth,
)
from bus.keys import ShowKeys, vehicle_id_from_key
from bus.messages import (
    MAX_ID_CHARS,
    MAX_TEXT_CHARS,
    AgentReport,
    JobState,
    OperatorCommand,
    SubmitRequest,
    Telemetry,
    VehicleCommand,
    VehicleStatus,
)


def test_keys_share_the_show_prefix_and_reject_wildcards() -> None:
    keys = ShowKeys("airshow-2014")
    assert keys.submit == "skyquill/airshow-2014/orchestrator/submit"
    assert keys.telemetry("uav2") == "skyquill/airshow-2014/vehicles/uav2/telemetry"
    assert vehicle_id_from_key(keys.vehicle_status("uav3")) == "uav3"
    for bad in ("", "a/b", "a*", "x$y"):
        with pytest.raises(ValueError):
            ShowKeys(bad)
    with pytest.raises(ValueError):
        keys.telemetry("**")


def test_requests_reject_unknown_fields_and_name_the_field() -> None:
    with pytest.raises(MessageError) as unknown:
        decode(b'{"text": "A", "colour": "red"}', SubmitRequest)
    assert "colour" in unknown.value.info.message
    with pytest.raises(MessageError) as wrong_type:
        decode(b'{"text": 5}', SubmitRequest)
    assert wrong_type.value.info.field == "$.text"
    with pytest.raises(MessageError) as bad_json:
        decode(b'{"text": ', SubmitRequest)
    assert bad_json.value.info.code == "bad_json"
    with pytest.raises(MessageError) as bad_command:
        decode(b'{"command": "self_destruct"}', OperatorCommand)
    assert bad_command.value.info.code == "invalid"


def test_a_status_without_preflight_reads_as_ready_and_one_with_it_round_trips() -> None:
    old = b'{"v": 1, "vehicle_id": "uav1", "kind": "quadrotor-brush", "state": "idle"}'
    assert decode(old, VehicleStatus).preflight == ""  # an agent from before the field
    why = "Preflight Fail: horizontal velocity unstable"
    status = VehicleStatus(vehicle_id="uav1", kind="quadrotor-brush", state="idle", preflight=why)
    assert decode(encode(status), VehicleStatus) == status


def test_oversized_payload_is_refused_before_parsing() -> None:
    payload = b'{"text": "' + b"x" * MAX_PAYLOAD_BYTES + b'"}'
    with pytest.raises(MessageError) as err:
        decode(payload, SubmitRequest)
    assert err.value.info.code == "too_large"


def test_published_state_tolerates_fields_from_newer_publishers() -> None:
    raw = (
        b'{"vehicle_id": "uav1", "t_s": 1.0, "state": "writing",'
        b' "position_m_enu": [1, 2, 3], "velocity_mps_enu": [0, 0, 0], "wind_mps": 3}'
    )
    telemetry = decode(raw, Telemetry)
    assert telemetry.position_m_enu == (1.0, 2.0, 3.0)


@given(
    job_id=st.text(min_size=1, max_size=20),
    label=st.text(max_size=20),
    progress=st.floats(0.0, 1.0),
    created=st.floats(0.0, 2e9),
)
def test_job_state_round_trips_through_json(
    job_id: str, label: str, progress: float, created: float
) -> None:
    job = JobState(
        job_id=job_id,
        state="queued",
        label=label,
        kind="text",
        client_id="kiosk",
        created_at_s=created,
        updated_at_s=created,
        progress=progress,
    )
    assert decode(encode(job), JobState) == job


# --- malformed payloads: always a MessageError with a stable code, never anything else ---------

REQUEST_TYPES = (SubmitRequest, OperatorCommand, AgentReport, VehicleCommand)
STROKES = b'{"units": "px", "y_axis": "up", "strokes": [[[0, 0], [1, 1]]]}'


def _code(payload: bytes, message_type: type[msgspec.Struct] = SubmitRequest) -> str:
    with pytest.raises(MessageError) as err:
        decode(payload, message_type)
    return err.value.info.code


@pytest.mark.parametrize("depth", [MAX_DEPTH + 1, 1_000, 100_000])
def test_deep_nesting_is_refused_before_parsing(depth: int) -> None:
    for opener, closer in ((b"[", b"]"), (b'{"a":', b"}")):
        payload = b'{"text": "A", "strokes": {"x": ' + opener * depth + closer * depth + b"}}"
        assert _code(payload) == "too_deep"
        assert _code(opener * depth) == "too_deep"  # unterminated too


def test_nesting_within_the_limit_and_brackets_inside_strings_are_fine() -> None:
    depth = MAX_DEPTH - 3  # the request object and "strokes" and "x" take 3 levels
    payload = b'{"text": "A", "strokes": {"x": ' + b"[" * depth + b"]" * depth + b"}}"
    assert decode(payload, SubmitRequest).strokes is not None
    brackets = b"[" * 5000 + b'\\"{' * 100 + b"\\\\"
    request = decode(b'{"text": "A", "strokes": {"note": "' + brackets + b'"}}', SubmitRequest)
    assert request.strokes is not None and request.strokes["note"].startswith("[[[")
    # an escaped backslash ends before the quote: the brackets after it are real nesting
    payload = b'{"text": "\\\\", "strokes": {"x": ' + b"[" * 40 + b"]" * 40 + b"}}"
    assert _code(payload) == "too_deep"


@settings(max_examples=200, deadline=None)
@given(
    st.recursive(
        st.none() | st.booleans() | st.integers() | st.text(alphabet='[]{}"\\ab'),
        lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=3), inner),
        max_leaves=60,
    )
)
def test_nesting_depth_matches_the_parsed_structure(value: Any) -> None:
    def depth(v: Any) -> int:
        if isinstance(v, list):
            return 1 + max((depth(x) for x in v), default=0)
        if isinstance(v, dict):
            return 1 + max((depth(x) for x in v.values()), default=0)
        return 0

    raw = json.dumps(value).encode()
    expected = depth(value)
    if raw.count(b"[") + raw.count(b"{") > MAX_DEPTH:  # below that the scan is skipped
        assert nesting_depth(raw) == expected


@settings(max_examples=300, deadline=None)
@given(
    st.binary(max_size=80) | st.lists(st.sampled_from(list(b'[]{}"\\a')), max_size=80).map(bytes)
)
def test_depth_without_numpy_is_the_vectorised_depth(raw: bytes) -> None:
    """Small texts are scanned with bytes and regex operations, large ones by numpy: the same."""
    assert _depth_scanned(raw) == _depth_vectorised(raw)


@pytest.mark.parametrize(
    "payload",
    [
        b'{"text": "\xff\xfe"}',
        b'{"text": "A", "strokes": {"label": "\xc3"}}',
        b'{"text": "A", "client_id": "\xed\xa0\x80"}',  # an encoded surrogate
        b'{"text": "\\ud800"}',  # a lone surrogate escape
    ],
)
def test_invalid_utf8_is_bad_json(payload: bytes) -> None:
    assert _code(payload) == "bad_json"


@pytest.mark.parametrize("literal", [b"NaN", b"Infinity", b"-Infinity", b"1e999", b"nan"])
def test_non_finite_numbers_are_refused(literal: bytes) -> None:
    code = _code(
        b'{"vehicle_id": "u", "job_id": "j", "event": "progress", "progress": ' + literal + b"}",
        AgentReport,
    )
    assert code in ("bad_json", "invalid")


REPORT = b'{"vehicle_id": "u", "job_id": "j", '
PLANNED = "$.planned_duration_s"
LONG_ID = b"j" * (MAX_ID_CHARS + 1)
LONG_TEXT = b"r" * (MAX_TEXT_CHARS + 1)


@pytest.mark.parametrize(
    ("payload", "message_type", "field"),
    [
        (b'{"text": "A", "priority": 1' + b"0" * 30 + b"}", SubmitRequest, "$.priority"),
        (b'{"command": "prioritize", "priority": 1001}', OperatorCommand, "$.priority"),
        (b'{"text": "A", "v": 99999999999}', SubmitRequest, "$.v"),
        (REPORT + b'"event": "progress", "progress": 1e308}', AgentReport, "$.progress"),
        (REPORT + b'"event": "done", "planned_duration_s": -1}', AgentReport, PLANNED),
        (REPORT + b'"event": "failed", "retry_after_s": 1e300}', AgentReport, "$.retry_after_s"),
        (b'{"command": "cancel", "job_id": "%s"}' % LONG_ID, OperatorCommand, "$.job_id"),
        (b'{"command": "pause", "reason": "%s"}' % LONG_TEXT, OperatorCommand, "$.reason"),
        (b'{"command": "cancel", "job_id": ""}', VehicleCommand, "$.job_id"),
        (b'{"text": "A", "client_id": "' + b"c" * 100_000 + b'"}', SubmitRequest, "$.client_id"),
    ],
)  # fmt: skip
def test_out_of_range_numbers_and_overlong_strings_name_the_field(
    payload: bytes, message_type: type[msgspec.Struct], field: str
) -> None:
    with pytest.raises(MessageError) as err:
        decode(payload, message_type)
    assert (err.value.info.code, err.value.info.field) == ("invalid", field)


def test_a_strokes_document_fits_in_a_request() -> None:
    request = decode(b'{"strokes": ' + STROKES + b', "priority": -10}', SubmitRequest)
    assert request.strokes is not None and request.priority == -10


@settings(max_examples=300, deadline=None)
@given(payload=st.binary(max_size=200), message_type=st.sampled_from(REQUEST_TYPES))
def test_any_bytes_decode_or_raise_message_error_only(
    payload: bytes, message_type: type[msgspec.Struct]
) -> None:
    try:
        decode(payload, message_type)
    except MessageError as exc:
        assert re.fullmatch(r"[a-z_]+", exc.info.code)
        assert exc.info.message


ROOT = Path(__file__).resolve().parents[1]
SENDERS = ("bus", "orchestrator", "vehicle_agent", "planner", "kiosk")
"""Packages whose error codes travel on the bus (the TUI's and CLI's own codes never do)."""
CODE_PATTERNS = (
    r'code="([a-z_]+)"',
    r'code = "([a-z_]+)"',
    r'_error\(\s*"([a-z_]+)"',
    r'refuse\(\s*"([a-z_]+)"',
    r'_refuse\(\s*"([a-z_]+)"',
    r'Breach\(\s*"([a-z_]+)"',
    r'_abort_job\(\s*"([a-z_]+)"',
    r'aborted\([^,]+,\s*"([a-z_]+)"',
    r'"vehicle_lost" if lost else "([a-z_]+)"',
)


def test_every_error_code_the_project_sends_is_documented() -> None:
    text = (ROOT / "docs" / "protocol.md").read_text(encoding="utf-8")
    table = text.split("Every `code` the project sends", 1)[1].split("\n\n", 2)[1]
    cells = [line.split("|")[1] for line in table.splitlines() if line.startswith("| `")]
    documented = {code for cell in cells for code in re.findall(r"`([a-z_]+)`", cell)}
    sent: dict[str, str] = {}
    for package in SENDERS:
        for path in (ROOT / package).rglob("*.py"):
            source = path.read_text(encoding="utf-8")
            for pattern in CODE_PATTERNS:
                for code in re.findall(pattern, source):
                    sent.setdefault(code, str(path.relative_to(ROOT)))
    assert {"bad_json", "too_deep", "plan_failed", "busy", "vehicle_lost"} <= sent.keys()
    missing = {code: where for code, where in sent.items() if code not in documented}
    assert not missing, f"codes sent but not in docs/protocol.md: {missing}"
