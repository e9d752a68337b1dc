"""A phrase handed in at the kiosk (``kiosk/limits.py``, ``kiosk/phrase_view.py``, the API):
2 to as many characters as the show has boards in a row, refused beyond with a one-line reason
naming the limit in both languages; it counts as its characters in the per-address limit; it is
sent as one phrase and followed as one ticket with each character's state, naming drones by
their board's place, never by an internal id.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from test_kiosk_api import assert_refused, wait_for
from test_kiosk_support import WAIT_S, Browser, FakeOrchestrator, sse_events

from bus.keys import ShowKeys
from bus.messages import ErrorInfo, JobMetrics, JobState, PhrasePlace, WrittenInk
from bus.session import BusSettings, loopback_settings, open_session
from kiosk.errors import RejectedError
from kiosk.jobs import JobBook
from kiosk.limits import SubmissionLimits, check_submission
from kiosk.service import serving
from kiosk.settings import KioskSettings, settings_from_show
from showfile import load_show

pytestmark = pytest.mark.timeout(120)

KEYS = ShowKeys("kiosk-phrase-test")
ROW = SubmissionLimits(max_text_chars=1, max_phrase_chars=4, blocklist=("坏蛋",))
STATIC = Path(__file__).resolve().parents[1] / "kiosk" / "static"
PLACES = {"uav1": 1, "uav2": 2, "uav3": 3, "uav4": 4}


def _check(body: dict[str, Any], limits: SubmissionLimits = ROW) -> Any:
    return check_submission(body, limits, has_glyph=lambda ch: ch != "☃")


def _refused(body: dict[str, Any], limits: SubmissionLimits = ROW) -> RejectedError:
    with pytest.raises(RejectedError) as caught:
        _check(body, limits)
    return caught.value


# --- what a phrase may be ---------------------------------------------------------------------


def test_a_phrase_of_two_to_the_row_is_taken_and_counts_as_its_characters() -> None:
    for text in ("新年", "新年快乐"):
        submission = _check({"text": text, "phrase": True})
        assert (submission.text, submission.phrase) == (text, True)
        assert submission.characters == len(text)
    lone = _check({"text": "永"})
    assert not lone.phrase and lone.characters == 1
    # the same four characters without ``phrase`` are a word on one board: over its limit
    assert _refused({"text": "新年快乐"}).code == "text_too_long"


def test_a_phrase_longer_than_the_row_is_refused_naming_the_limit_in_both_languages() -> None:
    refusal = _refused({"text": "新年快乐好", "phrase": True})
    assert refusal.code == "phrase_too_long" and refusal.status == 400
    assert "at most 4 characters" in refusal.message and "\n" not in refusal.message
    for lang, said in (("en", "at most 4 characters"), ("zh-Hans", "最多 4 个字")):
        words = json.loads((STATIC / "i18n" / f"{lang}.json").read_text(encoding="utf-8"))
        line = words[f"err_{refusal.code}"].replace("{n}", "4")
        assert said in line and "\n" not in line, (lang, line)


@pytest.mark.parametrize(
    ("body", "code"),
    [
        ({"text": "新", "phrase": True}, "phrase_too_short"),
        ({"text": "新年 快乐", "phrase": True}, "phrase_spaces"),
        ({"text": "  ", "phrase": True}, "empty"),
        ({"text": "新☃", "phrase": True}, "no_glyph"),
        ({"text": "坏蛋", "phrase": True}, "blocked_text"),
        ({"text": "新年", "phrase": "yes"}, "bad_request"),
        ({"strokes": {"strokes": []}, "phrase": True}, "bad_request"),
    ],
)
def test_what_is_no_phrase_is_refused(body: dict[str, Any], code: str) -> None:
    assert _refused(body).code == code


def test_a_show_with_one_board_takes_no_phrase() -> None:
    one = SubmissionLimits(max_phrase_chars=1)
    assert _refused({"text": "新年", "phrase": True}, one).code == "no_phrase"


def test_the_show_files_row_is_the_kiosks_phrase_limit() -> None:
    airshow = load_show(Path(__file__).resolve().parents[1] / "shows" / "airshow-2014.yaml")
    assert settings_from_show(airshow, port=0).limits.max_phrase_chars == len(airshow.boards) == 4


# --- one ticket, each character's state ------------------------------------------------------


def _state(index: int, state: str, **changes: Any) -> JobState:
    fields: dict[str, Any] = {
        "job_id": f"p{index}", "state": state, "label": "新年快乐"[index], "kind": "text",
        "client_id": "kiosk-1", "created_at_s": 1.0, "updated_at_s": time.time(),
        "phrase": PhrasePlace(phrase_id="p0", index=index, size=4),
    }  # fmt: skip
    fields.update(changes)
    return JobState(**fields)


def _ticket(book: JobBook) -> Any:
    job = book.add(session_id="s", label="新年快乐", preview=None, phrase_size=4)
    book.bind(job.ticket, "p0")
    return job


def test_a_phrase_is_one_ticket_that_follows_every_character() -> None:
    book = JobBook()
    job = _ticket(book)
    for i in range(4):
        assert book.update(_state(i, "queued", queue_position=i + 1, eta_s=100.0 + i))
        assert book.ticket_of(f"p{i}") == job.ticket  # any character wakes the one ticket
    view = book.view(job, PLACES)
    assert view["state"] == "queued" and view["queue_position"] == 1 and view["eta_s"] == 103.0
    assert "waits for 4 free drones side by side" in view["status_text"]
    assert [c["state"] for c in view["phrase"]["characters"]] == ["queued"] * 4

    for i in range(4):
        book.update(_state(i, "writing", vehicle_id=f"uav{i + 1}", progress=0.5, attempts=1))
    failed = ErrorInfo(code="requeued", message="快 failed; written again alone")
    book.update(_state(2, "queued", vehicle_id="uav3", attempts=1, progress=0.0, error=failed))
    view = book.view(job, PLACES)
    chars = view["phrase"]["characters"]
    assert [c["board"] for c in chars] == [1, 2, None, 4]
    assert [c["again"] for c in chars] == [False, False, True, False]  # failed, written again
    assert view["state"] == "writing"

    book.update(_state(2, "writing", vehicle_id="uav3", attempts=2, progress=0.2))
    for i in (0, 1, 3):
        book.update(_state(i, "done", vehicle_id=f"uav{i + 1}", progress=1.0, attempts=1))
    view = book.view(job, PLACES)
    assert view["phrase"]["written"] == 3 and not view["final"]
    assert (
        view["phrase"]["characters"][2]["again"] and view["phrase"]["characters"][2]["board"] == 3
    )
    book.update(_state(2, "done", vehicle_id="uav3", progress=1.0, attempts=2))
    view = book.view(job, PLACES)
    assert view["state"] == "done" and view["final"]
    assert (
        view["status_text"] == "Done! Your phrase was written by drones 1, 2, 3, 4, side by side."
    )
    shown = json.dumps(view, ensure_ascii=False)
    assert "uav" not in shown and not any(f'"p{i}"' in shown for i in (1, 2, 3))


def test_each_written_character_of_a_phrase_carries_the_ink_its_drone_left() -> None:
    book = JobBook()
    job = _ticket(book)
    ink = WrittenInk(width_px=8, height_px=2, extent_m_board=(-0.1, -0.1, 0.1, 0.1),
                     bits=bytes([0b10000001, 0b01111110]))  # fmt: skip
    metrics = JobMetrics(rmse_pen_down_m=0.004, rmse_m=0.005, max_error_m=0.01, iou=0.8,
                         duration_s=20.0, written=ink)  # fmt: skip
    for i in range(4):
        book.update(_state(i, "writing", vehicle_id=f"uav{i + 1}", progress=0.5, attempts=1))
    book.update(_state(1, "done", vehicle_id="uav2", progress=1.0, attempts=1, metrics=metrics))
    chars = book.view(job, PLACES)["phrase"]["characters"]
    assert [c["written"] is not None for c in chars] == [False, True, False, False]
    assert chars[1]["written"] == {
        "format": "bitmap1", "width_px": 8, "height_px": 2,
        "extent_m_board": [-0.1, -0.1, 0.1, 0.1], "bits": "gX4=",
    }  # fmt: skip
    # a later state without the picture (a snapshot's) keeps the one the drone reported
    lean = JobMetrics(rmse_pen_down_m=0.004, rmse_m=0.005, max_error_m=0.01, iou=0.8,
                      duration_s=20.0)  # fmt: skip
    book.update(_state(1, "done", vehicle_id="uav2", progress=1.0, attempts=1, metrics=lean))
    assert book.view(job, PLACES)["phrase"]["characters"][1]["written"] == chars[1]["written"]


def test_a_rejected_phrase_tells_the_operators_reason_once() -> None:
    book = JobBook()
    job = _ticket(book)
    said = ErrorInfo(code="rejected", message="x", reason="不适合展出")
    for i in range(4):
        book.update(_state(i, "rejected", error=said))
    view = book.view(job, PLACES)
    assert view["state"] == "rejected" and view["final"] and view["reason"] == "不适合展出"
    assert [c["state"] for c in view["phrase"]["characters"]] == ["rejected"] * 4


def test_a_phrase_whose_characters_are_not_all_known_yet_is_not_final() -> None:
    book = JobBook()
    job = _ticket(book)
    assert book.unknown(job)  # bound, nothing known: looked up from the orchestrator
    book.update(_state(0, "done", vehicle_id="uav1", progress=1.0))
    view = book.view(job, PLACES)
    assert not view["final"] and view["phrase"]["characters"][1]["state"] == "checking"
    assert book.unknown(job)


# --- over the bus: sent as one phrase, limited by its characters, followed as one ticket ---------


@pytest.fixture(scope="module")
def bus() -> Iterator[tuple[BusSettings, FakeOrchestrator]]:
    settings = loopback_settings()
    with (
        open_session(settings, role="router"),
        open_session(settings, role="client") as orchestrator_session,
    ):
        fake = FakeOrchestrator(orchestrator_session, KEYS).start()
        yield settings, fake
        fake.stop()


@pytest.fixture(scope="module")
def kiosk(bus: tuple[BusSettings, FakeOrchestrator]) -> Iterator[str]:
    settings = KioskSettings(
        show_id=KEYS.show_id, port=0, limits=ROW, rate_limit_per_minute=6, submit_timeout_s=2.0,
        places=PLACES,
    )  # fmt: skip
    with serving(settings, bus[0], role="client") as server:
        yield server.url


def test_a_phrase_counts_as_its_characters_in_the_per_address_limit(
    kiosk: str, bus: tuple[BusSettings, FakeOrchestrator]
) -> None:
    fake = bus[1]
    visitor = Browser(kiosk)
    reply = visitor.post("/api/submit", {"text": "新年快乐", "phrase": True})
    assert reply.status == 200, reply.body
    request = fake.requests[-1]
    assert (request.text, request.phrase) == ("新年快乐", True)
    sent = len(fake.requests)
    # 4 of 6 spent: three more characters are over the limit, whatever their form
    message = assert_refused(visitor.post("/api/submit", {"text": "新年快", "phrase": True}),
                             429, "rate_limited")  # fmt: skip
    assert "wait" in message and len(fake.requests) == sent  # nothing was sent
    assert visitor.post("/api/submit", {"text": "永"}).status == 429
    assert Browser(kiosk).post("/api/submit", {"text": "永"}).status == 200  # another address
    too_long = Browser(kiosk).post("/api/submit", {"text": "新年快乐好", "phrase": True})
    assert "at most 4 characters" in assert_refused(too_long, 400, "phrase_too_long")


def test_the_phrase_preview_plans_every_character_for_adjacent_boards(kiosk: str) -> None:
    reply = Browser(kiosk).post("/api/preview", {"text": "新年", "phrase": True})
    assert reply.status == 200, reply.body
    preview = reply.body["preview"]
    assert preview["phrase"] and preview["row"] == 4
    assert [c["label"] for c in preview["characters"]] == ["新", "年"]
    assert all(c["path"] and c["turning_point_count"] > 0 for c in preview["characters"])
    longest = max(c["duration_s"] for c in preview["characters"])
    assert preview["duration_s"] == longest  # they write at once


def test_the_ticket_of_a_phrase_follows_its_characters_over_the_bus(
    kiosk: str, bus: tuple[BusSettings, FakeOrchestrator]
) -> None:
    fake = bus[1]
    visitor = Browser(kiosk)
    reply = visitor.post("/api/submit", {"text": "新年快乐", "phrase": True})
    assert reply.status == 200, reply.body
    first, token = reply.body["job_id"], reply.body["token"]
    assert reply.body["job"]["phrase"]["size"] == 4
    place = {"phrase_id": first, "size": 4}
    ids = [first] + [f"{first}-{i}" for i in (1, 2, 3)]
    for i, job_id in enumerate(ids):
        fake.set_state(job_id, "queued", label="新年快乐"[i], queue_position=1, eta_s=70.0,
                       phrase=PhrasePlace(index=i, **place))  # fmt: skip
    path = f"/api/jobs/{reply.body['ticket']}?token={token}"
    view = wait_for(
        lambda: (
            (j := visitor.get(path).body["job"]).get("phrase")
            and all(c["state"] == "queued" for c in j["phrase"]["characters"])
            and j
        ),
        "every character known",
    )
    assert "waits for 4 free drones" in view["status_text"] and view["eta_s"] == 70.0

    frames = sse_events(kiosk, f"/api/jobs/{reply.body['ticket']}/events?token={token}")
    events = (d for n, d in frames if n == "job")
    next(events)
    for i, job_id in enumerate(ids):
        fake.set_state(job_id, "done", vehicle_id=f"uav{i + 1}", progress=1.0,
                       queue_position=None)  # fmt: skip
    deadline = time.monotonic() + WAIT_S
    for view in events:  # the one stream wakes for each character and ends when all are done
        assert time.monotonic() < deadline
        if view["final"]:
            break
    assert view["state"] == "done" and view["phrase"]["written"] == 4
    assert [c["board"] for c in view["phrase"]["characters"]] == [1, 2, 3, 4]
