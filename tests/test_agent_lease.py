"""The agent's hold on its job (``vehicle_agent/lease.py``)."""

from __future__ import annotations

from vehicle_agent.lease import JobLease

LOST_AFTER_S = 1.5


def test_a_stall_of_lost_after_s_voids_the_lease_in_any_phase_a_shorter_one_does_not() -> None:
    lease = JobLease(LOST_AFTER_S)
    lease.hold("j1", active=True, writing=False, now_s=0.0)
    lease.tick_done(0.0)
    assert lease.breach(lease.tick(1.4), 1.4) is None  # 1.4 s: the orchestrator may still see it
    lease.tick_done(1.4)
    why = lease.breach(lease.tick(1.4 + LOST_AFTER_S), 1.4 + LOST_AFTER_S)
    assert why == "this agent stalled for 1.5 s"
    assert JobLease(LOST_AFTER_S).breach(10.0, 10.0) is None  # no job: nothing to give up


def test_writing_needs_a_confirmation_younger_than_the_lease_not_only_a_recent_start() -> None:
    lease = JobLease(LOST_AFTER_S)
    lease.hold("j1", active=True, writing=False, now_s=0.0)  # assigned at 0; transit takes 5 s
    assert lease.breach(0.0, 4.0) is None  # unconfirmed in transit: no ink, nothing to give up
    lease.hold("j1", active=True, writing=True, now_s=5.0)
    # the brush would touch 5 s after the last word from the orchestrator: it may have given
    # the job away meanwhile (the old rule counted from the start of writing and wrote on)
    assert lease.breach(0.0, 5.0) == "no acknowledgement from the orchestrator for 5.0 s"


def test_a_flown_job_asks_for_confirmations_before_and_while_writing() -> None:
    lease = JobLease(LOST_AFTER_S)
    lease.hold("j1", active=True, writing=False, now_s=0.0)
    assert not lease.wants_probe(0.4) and lease.wants_probe(0.5)  # in transit too
    lease.acknowledged("j1", sent_at_s=4.9)
    lease.hold("j1", active=True, writing=True, now_s=5.0)
    assert lease.breach(0.0, 5.0) is None and not lease.wants_probe(5.3)
    assert lease.wants_probe(5.4)
    lease.acknowledged("j1", sent_at_s=5.5)
    lease.acknowledged("j0", sent_at_s=6.9)  # another job's receipt proves nothing
    assert lease.breach(0.0, 6.9) is None
    assert lease.breach(0.0, 7.0) == "no acknowledgement from the orchestrator for 1.5 s"
    lease.hold(None, active=False, writing=False, now_s=7.0)
    assert lease.job_id is None and lease.breach(0.0, 99.0) is None


def test_a_job_no_longer_flown_asks_nothing() -> None:
    lease = JobLease(LOST_AFTER_S)
    lease.hold("j1", active=False, writing=False, now_s=0.0)  # returning, its result on its way
    assert not lease.wants_probe(10.0)


def test_unconfirmed_writing_asks_for_a_confirmation_at_most_once_a_third_of_the_lease() -> None:
    lease = JobLease(LOST_AFTER_S)  # probes every 0.5 s
    lease.hold("j1", active=True, writing=True, now_s=0.0)
    assert not lease.probe_due(0.4)
    asked = [t for t in (0.5, 0.6, 0.9, 1.0, 1.2) if lease.probe_due(t)]
    assert asked == [0.5, 1.0]
    lease.acknowledged("j1", sent_at_s=1.2)
    assert not lease.probe_due(1.6)  # confirmed at 1.2: nothing to ask before 1.7


def test_a_later_job_starts_with_a_fresh_lease() -> None:
    lease = JobLease(LOST_AFTER_S)
    lease.hold("j1", active=True, writing=True, now_s=0.0)
    lease.hold("j2", active=True, writing=True, now_s=10.0)
    assert lease.breach(0.0, 11.0) is None and lease.confirmed_at_s == 10.0


def test_the_brush_goes_down_only_soon_after_an_acknowledged_ready_report() -> None:
    lease = JobLease(LOST_AFTER_S, time_scale=2.0)
    lease.hold("j1", active=True, writing=False, now_s=0.0)
    lease.acknowledged("j1", sent_at_s=4.0)  # a probe: the job is still ours, but no ready
    assert not lease.may_begin_writing(4.1) and lease.fence_at_s is None
    assert lease.ready_due(4.1) and not lease.ready_due(4.2)  # sent; again after 0.5 s
    assert lease.ready_due(4.6)  # still unacknowledged: sent again
    lease.acknowledged("j1", sent_at_s=4.6, ready_writing_s=10.0)
    assert lease.may_begin_writing(6.0) and not lease.may_begin_writing(6.1)
    assert lease.fence_at_s == 4.6 + LOST_AFTER_S + 1.5 * 10.0 / 2.0
    assert not lease.ready_due(5.0) and lease.ready_due(5.1)  # fresh for a third of the lease
    lease.acknowledged("j1", sent_at_s=5.1, ready_writing_s=10.0)
    assert lease.fence_at_s == 5.1 + LOST_AFTER_S + 7.5  # the latest one counts
    lease.acknowledged("j1", sent_at_s=4.8, ready_writing_s=10.0)  # an older one's late answer
    assert lease.fence_at_s == 5.1 + LOST_AFTER_S + 7.5 and lease.ready_at_s == 5.1
    lease.hold("j2", active=True, writing=False, now_s=6.0)  # the next job: nothing carried over
    assert not lease.may_begin_writing(6.0) and lease.fence_at_s is None and lease.ready_due(6.0)
