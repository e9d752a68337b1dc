"""Queue ETAs (orchestrator.fleet.queue_etas): known answers and list-scheduling properties."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bus.messages import JobStateName
from orchestrator.fleet import EtaModel, queue_etas, remaining_s
from orchestrator.jobs import Job

MODEL = EtaModel(time_scale=1.0, before_write_s=10.0, after_write_s=6.0)
NOW = 1000.0


def job(
    job_id: str,
    state: JobStateName = "queued",
    estimate_s: float = 20.0,
    **extra: object,
) -> Job:
    return Job(
        job_id=job_id,
        seq=int(job_id.strip("jabc") or 0),
        state=state,
        kind="text",
        text="L",
        label="L",
        client_id="c",
        created_at_s=0.0,
        updated_at_s=0.0,
        estimate_s=estimate_s,
        **extra,  # type: ignore[arg-type]
    )


def test_idle_vehicles_on_their_own_boards_take_jobs_in_turn() -> None:
    queue = [job("j1"), job("j2"), job("j3")]
    etas = queue_etas(queue, [], {"v1": "b1", "v2": "b2"}, NOW, MODEL)
    # j1, j2 at once (approach 10 s); j3 when v1 is back: 10 + 20 written + 6 landed + 10
    assert etas == {"j1": 10.0, "j2": 10.0, "j3": 46.0}


def test_vehicles_sharing_a_board_take_turns_on_it() -> None:
    queue = [job("j1"), job("j2")]
    etas = queue_etas(queue, [], {"v1": "b", "v2": "b"}, NOW, MODEL)
    # j2 waits for the board (free when j1 is written, at 30 s), then its own approach
    assert etas == {"j1": 10.0, "j2": 40.0}


def test_active_jobs_count_what_is_left_of_them() -> None:
    writing = job(
        "a1",
        "writing",
        estimate_s=99.0,
        planned_duration_s=40.0,
        progress=0.5,
        vehicle_id="v1",
        board_id="b1",
    )
    assert remaining_s(writing, NOW, MODEL) == 20.0  # the planned duration wins over estimate
    etas = queue_etas([job("j1")], [writing], {"v1": "b1"}, NOW, MODEL)
    assert etas == {"j1": 20.0 + 6.0 + 10.0}
    approaching = job("a2", "assigned", vehicle_id="v1", board_id="b1", assigned_at_s=NOW - 4.0)
    assert remaining_s(approaching, NOW, MODEL) == 6.0 + 20.0
    etas = queue_etas([job("j1")], [approaching], {"v1": "b1"}, NOW, MODEL)
    assert etas == {"j1": 26.0 + 6.0 + 10.0}


def test_time_scale_divides_every_sim_duration() -> None:
    fast = EtaModel(time_scale=2.0, before_write_s=10.0, after_write_s=6.0)
    approaching = job("a1", "assigned", vehicle_id="v1", board_id="b1", assigned_at_s=NOW - 2.0)
    # 2 s of wall are 4 s of approach: 6 + 20 sim left, + 6 landing + 10 approach = 42 sim s
    assert queue_etas([job("j1")], [approaching], {"v1": "b1"}, NOW, fast) == {"j1": 21.0}


def test_a_busy_board_blocks_vehicles_that_share_it_even_unusable_ones_jobs() -> None:
    paused_vehicles_job = job("a1", "writing", vehicle_id="v9", board_id="b", progress=0.0)
    etas = queue_etas([job("j1")], [paused_vehicles_job], {"v1": "b"}, NOW, MODEL)
    assert etas == {"j1": 20.0 + 10.0}


def test_a_landing_vehicle_is_free_after_half_the_landing_time() -> None:
    etas = queue_etas([job("j1")], [], {"v1": "b1"}, NOW, MODEL, landing=["v1"])
    assert etas == {"j1": 3.0 + 10.0}


def test_no_usable_vehicle_no_eta() -> None:
    assert queue_etas([job("j1")], [], {}, NOW, MODEL) == {}


@given(
    st.lists(st.floats(1.0, 120.0), min_size=1, max_size=12),
    st.lists(st.sampled_from(["b1", "b2", "b3"]), min_size=1, max_size=5),
)
def test_starts_follow_queue_order_and_never_beat_the_approach(
    durations: list[float], boards: list[str]
) -> None:
    queue = [job(f"j{k}", estimate_s=d) for k, d in enumerate(durations)]
    usable = {f"v{k}": b for k, b in enumerate(boards)}
    etas = [queue_etas(queue, [], usable, NOW, MODEL)[j.job_id] for j in queue]
    assert etas == sorted(etas)
    assert etas[0] == pytest.approx(MODEL.before_write_s)
    # one board's jobs never overlap: at most one job per distinct board starts per cycle
    distinct = len(set(boards))
    shortest = MODEL.before_write_s + min(durations)
    for k in range(distinct, len(etas)):
        assert etas[k] >= etas[k - distinct] + shortest - 1e-9
