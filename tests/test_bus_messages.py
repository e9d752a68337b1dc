"""The wire contract: keys are well-formed and payload errors say what and where."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bus.keys import ShowKeys, vehicle_id_from_key
from bus.messages import (
    MAX_PAYLOAD_BYTES,
    JobState,
    MessageError,
    OperatorCommand,
    SubmitRequest,
    Telemetry,
    decode,
    encode,
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
