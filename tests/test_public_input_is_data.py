"""What the public (or anything on the bus) writes is data: shown literally, never obeyed.

A real orchestrator hosts the show's Zenoh router on loopback; the real kiosk serves HTTP on it; the
operator console runs under Pilot on its own Zenoh session. Hostile strings go in by every way the
public has: typed text through the kiosk's HTTP API, a submission straight to the orchestrator's
``submit`` queryable (a drawing's ``label`` and the ``client_id``, which only the kiosk fixes:
refused at decode when they hold control codes, bidirectional overrides or markup), and
messages published on the bus (a 10 kB label, vehicle and event messages). The console must keep
running and show each string as the characters it is: markup as brackets, control codes as their
visible pictures, bidirectional overrides replaced, long strings cut. The flight report draws a
label with ``$...$`` as text, not as matplotlib mathtext.
"""

from __future__ import annotations

import asyncio
import io
import json
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from rich.console import Console
from test_kiosk_support import Browser
from test_tui_orchestrator import Orchestrator, moderated_show, until
from textual.widget import Widget

from bus.keys import ShowKeys
from bus.messages import (
    ErrorInfo,
    Event,
    JobState,
    SubmitReply,
    SubmitRequest,
    Telemetry,
    VehicleStatus,
)
from bus.pubsub import publish
from bus.rpc import query_one
from bus.session import Session, open_session
from cli.main import main as skyquill
from kiosk.service import serving
from kiosk.settings import settings_from_show
from tui.app import ConsoleApp
from tui.link import ConsoleLink
from tui.settings import settings_from_show as console_settings
from tui.widgets.confirm_screen import ConfirmScreen
from tui.widgets.vehicle_detail_screen import VehicleDetailScreen
from vehicles.picture import TITLE_MAX_CHARS, plain_title

pytestmark = [pytest.mark.timeout(120), pytest.mark.slow]

DATA = Path(__file__).parent / "data"
SIZE = (200, 60)
TYPED = ["[/x]", "[bold red]boo", "[link=e.v]x[/]", r"$\frac{1}{0}$"]
"""Typed at the kiosk: printable ASCII, every character has a Hershey glyph."""
CONTROL_LABEL = "\x1b[31mred\x00 \r\u202eevil\u2066 [bold red]x"
"""A drawing's own label, sent straight to the orchestrator: escape codes, NUL, CR, bidi."""
CLIENT_ID = "[/x]\x1b]8;;http://e.vil\x07\u202eid"
"""A client id of a submission sent straight to the orchestrator (the kiosk sets its own)."""
VEHICLE = "[@click=app.quit]\x1b[2J\u202erogue"
"""A vehicle id on the bus: action markup, a clear-screen code and a right-to-left override
(key expressions forbid ``/``, so no closing tag here)."""
LONG_LABEL = "[/x]" + "W" * 10_000
EVIL = ("\x1b", "\x00", "\r", "\x07", "\u202e", "\u2066")
"""Characters that must never reach the terminal."""


def screen_text(app: ConsoleApp) -> str:
    """The characters on the console's screen now (as a terminal would show them)."""
    width, height = app.size
    console = Console(width=width, height=height, file=io.StringIO(), force_terminal=True,
                      color_system="truecolor", record=True, legacy_windows=False,
                      safe_box=False)  # fmt: skip
    console.print(app.screen._compositor.render_update(full=True))
    return console.export_text(styles=False)


def submit_direct(session: Session, keys: ShowKeys, request: SubmitRequest) -> str:
    reply = query_one(session, keys.submit, request, SubmitReply, timeout_s=10.0)
    assert reply.ok and reply.job_id is not None, reply
    return reply.job_id


def publish_hostile_bus_messages(session: Session, keys: ShowKeys) -> None:
    """What a rogue or buggy publisher could put on the bus (no access control in this test)."""
    now = time.time()
    rogue = JobState(job_id="rogue-1", state="failed", label=LONG_LABEL, kind="text",
                     client_id=LONG_LABEL, created_at_s=now, updated_at_s=now,
                     error=ErrorInfo(code="x", message="[/x] \x1b[2J boom \u202e"))  # fmt: skip
    publish(session, keys.job("rogue-1"), rogue)
    writing = JobState(job_id="rogue-2", state="writing", label=LONG_LABEL, kind="text",
                       client_id="c", created_at_s=now, updated_at_s=now, vehicle_id=VEHICLE,
                       progress=0.5)  # fmt: skip
    publish(session, keys.job("rogue-2"), writing)
    status = VehicleStatus(vehicle_id=VEHICLE, kind="[bold]kind\x1b[0m", state="writing",
                           board_id="b1", job_id="rogue-2",
                           message="[/x]\x1b[31m vehicle says \r\u202ehi")  # fmt: skip
    publish(session, keys.vehicle_status(VEHICLE), status)
    telemetry = Telemetry(vehicle_id=VEHICLE, t_s=0.0, state="writing",
                          position_m_enu=(-3.0, 0.0, 0.8), velocity_mps_enu=(0.0, 0.0, 0.0),
                          reference_m_enu=(-3.0, 0.0, 0.8), pen_down=True, tracking_error_m=0.2,
                          job_id="rogue-2", progress=0.5)  # fmt: skip
    publish(session, keys.telemetry(VEHICLE), telemetry)
    event = Event(time_s=now, level="alert", kind="[/x]\x1b[5m", vehicle_id=VEHICLE,
                  message="[link=http://e.vil]event[/link]\x00\u2066")  # fmt: skip
    publish(session, keys.events, event)


def assert_shown_as_data(text: str, where: str) -> None:
    for ch in EVIL:
        assert ch not in text, f"{ch!r} reached the terminal on the {where}"
    assert "W" * (SIZE[0] // 2) not in text, f"a 10 kB label was not cut on the {where}"


def pane_text(screen: str, widget: Widget) -> str:
    """What ``widget`` shows on ``screen``, its lines joined without spaces (text wraps there)."""
    region = widget.content_region
    lines = screen.splitlines()[region.y : region.bottom]
    return "".join(line[region.x : region.right] for line in lines).replace(" ", "")


async def select_each_job(
    app: ConsoleApp, pilot: Any, wanted: set[str]
) -> dict[str, tuple[str, str]]:
    """Move the queue cursor over every job: the screen and the preview pane with each one. Rows
    may move under the cursor (a resync with the orchestrator's snapshot drops the rogue jobs),
    so the walk starts again from the top until every job of ``wanted`` was seen (three walks)."""
    app._queue.focus()
    shown: dict[str, tuple[str, str]] = {}
    for _ in range(3):
        await pilot.press("home")
        for _ in range(app._queue.row_count):
            await pilot.pause(0.05)
            app.redraw()
            await pilot.pause()
            job_id = app._queue.selected_job
            assert job_id is not None
            screen = screen_text(app)
            shown[job_id] = (screen, pane_text(screen, app._preview))
            await pilot.press("down")
        if wanted <= shown.keys():
            break
    return shown


def test_hostile_strings_reach_the_console_as_plain_text(tmp_path: Path) -> None:
    show = moderated_show(tmp_path)
    keys = ShowKeys(show.show_id)
    kiosk_settings = settings_from_show(show, port=0)
    kiosk_settings = replace(
        kiosk_settings, limits=replace(kiosk_settings.limits, max_text_chars=64)
    )
    with (
        Orchestrator(show),
        open_session(show.zenoh, role="client") as session,
        serving(kiosk_settings, show.zenoh, role="client") as kiosk,
    ):
        typed: dict[str, str] = {}
        for text in TYPED:
            reply = Browser(kiosk.url).post("/api/submit", {"text": text})
            assert reply.status == 200, reply.body
            typed[reply.body["job_id"]] = text
        drawing = json.loads((DATA / "l_tick_m_up.json").read_text(encoding="utf-8"))
        via_kiosk = Browser(kiosk.url).post(
            "/api/submit", {"strokes": {**drawing, "label": CONTROL_LABEL}}
        )
        assert via_kiosk.status == 200, via_kiosk.body
        for hostile in ({"strokes": {**drawing, "label": CONTROL_LABEL}},
                        {"text": "A", "client_id": CLIENT_ID}):  # fmt: skip
            refused = query_one(session, keys.submit, json.dumps(hostile).encode(), SubmitReply)
            assert refused.error is not None and refused.error.code == "invalid", refused
            assert "public text is plain text" in refused.error.message
        direct_text = submit_direct(session, keys, SubmitRequest(text="[bold red]", client_id="c"))
        app = ConsoleApp(console_settings(show), link=ConsoleLink(session, keys))
        expected = {*typed, via_kiosk.body["job_id"], direct_text}

        def jobs_known(*more: str) -> bool:
            return {*expected, *more} <= {row.job.job_id for row in app.model.queue_rows()}

        async def scenario(pilot: Any) -> None:
            await until(pilot, jobs_known, "every submission")  # late joiner: from the snapshot
            # live, to the subscriptions; a rogue publisher repeats itself (and a resync with the
            # orchestrator's snapshot rightly forgets jobs the orchestrator does not know)
            deadline = time.monotonic() + 20.0
            while not jobs_known("rogue-1", "rogue-2"):
                assert time.monotonic() < deadline, "console never showed the rogue jobs"
                publish_hostile_bus_messages(session, keys)
                await pilot.pause(0.5)
            await until(pilot, lambda: app.model.vehicle_row(VEHICLE, 0.0), "the rogue vehicle")
            # the kiosk passed on the drawing, not the label the page never sends
            drawn = app.model.job(via_kiosk.body["job_id"])
            assert drawn is not None and drawn.label.startswith("drawing (")
            shown = await select_each_job(app, pilot, expected)
            for job_id, (screen, _) in shown.items():
                assert_shown_as_data(screen, f"main screen with {job_id} selected")
            for job_id, label in typed.items():  # the preview pane shows the whole text
                assert label.replace(" ", "") in shown[job_id][1], f"{label!r} not shown as is"
            assert "[boldred]" in shown[direct_text][1]
            screen = shown[direct_text][0]
            assert "[/x]WWWWWWW…" in screen  # the 10 kB label, cut
            assert "[/x] ␛[2J boom \ufffd" in screen  # the failed job's error
            assert "[link=http://e.vil]event[/link]␀\ufffd" in screen  # an event
            assert "[@click=app.quit]␛[2J\ufffdrogue tracking error" in screen  # an alert
            # approve a job whose label is markup: the answer is shown too
            while app._queue.selected_job != next(iter(typed)):
                await pilot.press("up")
            await pilot.press("a")
            await until(pilot, lambda: app.model.last_reply is not None, "the answer")
            # the rogue vehicle's detail screen and its emergency-stop question
            app._fleet.focus()
            while app._fleet.selected_vehicle != VEHICLE:
                await pilot.press("down")
            await pilot.press("enter")
            await until(pilot, lambda: isinstance(app.screen, VehicleDetailScreen), "details")
            await pilot.pause(0.2)
            detail = screen_text(app)
            assert_shown_as_data(detail, "detail screen")
            assert "[@click=app.quit]␛[2J\ufffdrogue" in detail
            assert "[/x]␛[31m vehicle says ␍\ufffdhi" in detail
            await pilot.press("e")
            await until(pilot, lambda: isinstance(app.screen, ConfirmScreen), "the question")
            await pilot.pause(0.1)
            question = screen_text(app)
            assert_shown_as_data(question, "emergency-stop question")
            assert "EMERGENCY STOP [@click=app.quit]␛[2J\ufffdrogue?" in question
            await pilot.press("n")
            await pilot.press("escape")
            await pilot.pause(0.1)

        async def run() -> None:
            async with app.run_test(size=SIZE) as pilot:
                await scenario(pilot)

        asyncio.run(run())


def test_a_flight_report_draws_a_hostile_label_as_text(tmp_path: Path) -> None:
    label = r"$\frac{1}{0}$ $\x$ " + CONTROL_LABEL + " [/x]"
    strokes = json.loads((DATA / "l_tick_m_up.json").read_text(encoding="utf-8"))
    path = tmp_path / "hostile.json"
    path.write_text(json.dumps({**strokes, "label": label}), encoding="utf-8")
    out = tmp_path / "report"
    assert skyquill(["fly", "--strokes", str(path), "--height", "0.5", "--report", str(out)]) == 0
    assert (out / "report.png").read_bytes().startswith(b"\x89PNG")
    title = plain_title(LONG_LABEL + CONTROL_LABEL)
    assert len(title) == TITLE_MAX_CHARS and title.endswith("...")
    assert plain_title(CONTROL_LABEL) == ("U+001B[31mredU+0000 U+000DU+202EevilU+2066 [bold red]x")
