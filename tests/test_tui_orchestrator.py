"""The console against the real orchestrator (in a thread, hosting the Zenoh router on loopback)."""

from __future__ import annotations

import asyncio
import contextlib
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from bus.keys import ShowKeys
from bus.messages import JobState, OperatorCommand, ShowSnapshot, SubmitReply, SubmitRequest
from bus.rpc import query_one
from bus.session import free_tcp_endpoint, open_session
from orchestrator.app import serve_show
from showfile import Show, dump_show, load_show
from tui.app import ConsoleApp
from tui.commands import clear_fault
from tui.link import ConsoleLink
from tui.records import FINAL_JOB_STATES
from tui.settings import settings_from_show

pytestmark = [pytest.mark.timeout(90), pytest.mark.slow]

SHOWS = Path(__file__).resolve().parents[1] / "shows"


def moderated_show(tmp_path: Path) -> Show:
    """The airshow on a free loopback port, with moderation on and files in ``tmp_path``."""
    base = load_show(SHOWS / "airshow-2014.yaml")
    endpoint = free_tcp_endpoint()
    show = base.model_copy(
        update={
            "show_id": "tui-orchestrator",
            "zenoh": base.zenoh.model_copy(
                update={"router_listen": (endpoint,), "connect": (endpoint,)}
            ),
            "storage": base.storage.model_copy(
                update={
                    "database": tmp_path / "show.sqlite3",
                    "recordings_dir": tmp_path / "rec",
                    "record": False,
                }
            ),
            "policy": base.policy.model_copy(update={"moderation": True}),
            "security": base.security.model_copy(update={"mode": "none"}),  # loopback only
        }
    )
    path = tmp_path / "show.yaml"
    dump_show(show, path)
    return load_show(path)


class Orchestrator:
    """``serve_show`` on its own event loop in a thread; stopped on exit."""

    def __init__(self, show: Show) -> None:
        self.show = show
        self.ready = threading.Event()
        self.error: BaseException | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._thread = threading.Thread(target=self._main, daemon=True)

    def _main(self) -> None:
        async def body() -> None:
            self._loop, self._stop = asyncio.get_running_loop(), asyncio.Event()
            ready = asyncio.Event()
            task = asyncio.create_task(
                serve_show(self.show, role="router", stop=self._stop, ready=ready)
            )
            await ready.wait()
            self.ready.set()
            await task

        try:
            asyncio.run(body())
        except BaseException as exc:
            self.error = exc
            self.ready.set()

    def __enter__(self) -> Orchestrator:
        self._thread.start()
        assert self.ready.wait(20.0) and self.error is None, self.error
        return self

    def __exit__(self, *_: object) -> None:
        if self._loop is not None and self._stop is not None:
            self._loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(20.0)
        assert self.error is None, self.error


async def until(pilot: Any, condition: Callable[[], object], what: str) -> None:
    deadline = time.monotonic() + 20.0
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"console never showed: {what} ({_console_state(pilot.app)})")
        await pilot.pause(0.05)


def _console_state(app: ConsoleApp) -> str:
    """What the console knew when a wait ran out: the orchestrator, its snapshot, the jobs, the
    queue's selection and the event log's last lines (a fresh clone's CI once saw no selection
    for 20 s, which no local run at load 3 reproduced: 0.01 s)."""
    model = app.model
    last = [e.message for _, e in model.events.after(0)][-4:]
    return (
        f"orchestrator {model.orchestrator}, snapshot at {model.last_snapshot_s}, jobs"
        f" {sorted(model._jobs)}, selected {app._queue.selected_job}, events {last}"
    )


def test_console_approves_and_pauses_with_the_real_orchestrator(tmp_path: Path) -> None:
    show = moderated_show(tmp_path)
    keys = ShowKeys(show.show_id)
    with Orchestrator(show), open_session(show.zenoh, role="client") as session:
        reply = query_one(
            session,
            keys.submit,
            SubmitRequest(text="永", client_id="test"),
            SubmitReply,
            timeout_s=10.0,
        )
        assert reply.ok and reply.state == "awaiting_approval", reply
        job_id = reply.job_id
        app = ConsoleApp(settings_from_show(show), link=ConsoleLink(session, keys))

        async def scenario(pilot: Any) -> None:
            # Late joiner: the submission was made before the console started.
            await until(pilot, lambda: app._queue.selected_job == job_id, "the submission")
            assert app.model.orchestrator == "online"
            app._queue.focus()
            await pilot.press("a")
            await until(
                pilot,
                lambda: getattr(app.model.job(job_id), "state", None) in ("queued", "assigned"),
                "the job approved",
            )
            assert app.model.last_reply is not None and app.model.last_reply[1].ok
            await pilot.press("p")
            await until(pilot, lambda: app._header.queue_paused, "the queue paused")
            await pilot.press("p")
            await until(pilot, lambda: not app._header.queue_paused, "the queue resumed")
            # The orchestrator's event log reaches the console: one line per accepted command.
            await until(
                pilot,
                lambda: len([e for _, e in app.model.events.after(0) if e.kind == "operator"]) == 3,
                "three operator events",
            )
            logged = [e.message for _, e in app.model.events.after(0) if e.kind == "operator"]
            for line, command in zip(logged, ["approve", "pause", "resume"], strict=True):
                assert command in line

        async def main() -> None:
            async with app.run_test(size=(100, 30)) as pilot:
                await scenario(pilot)

        asyncio.run(main())


class UnansweredAtFirst(ConsoleLink):
    """A link whose asks for the snapshot go unanswered for its first :attr:`busy_s`, as from an
    orchestrator too busy to reply within an ask's 2 s (the console asks on start and again
    when the orchestrator's token appears, maybe twice: all of those are lost)."""

    busy_s = 3.0

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        self.created_s = time.monotonic()
        self.lost = 0

    async def query_snapshot(self, timeout_s: float = 2.0) -> ShowSnapshot | None:
        if time.monotonic() - self.created_s < self.busy_s:
            self.lost += 1
            return None
        return await super().query_snapshot(timeout_s)


@contextlib.contextmanager
def console_after_a_submission(
    tmp_path: Path, link_type: type[ConsoleLink]
) -> Iterator[tuple[ConsoleApp, str]]:
    """The real orchestrator with 永 submitted (awaiting approval), and a console (not yet
    running) that joins it through a ``link_type`` link; yields the console and the job's id."""
    show = moderated_show(tmp_path)
    keys = ShowKeys(show.show_id)
    with Orchestrator(show), open_session(show.zenoh, role="client") as session:
        request = SubmitRequest(text="永", client_id="test")
        reply = query_one(session, keys.submit, request, SubmitReply, timeout_s=10.0)
        assert reply.ok and reply.job_id is not None, reply
        yield ConsoleApp(settings_from_show(show), link=link_type(session, keys)), reply.job_id


def test_a_console_whose_first_asks_go_unanswered_asks_again_until_it_has_the_show(
    tmp_path: Path,
) -> None:
    with console_after_a_submission(tmp_path, UnansweredAtFirst) as (app, _job_id):
        link = app.link
        assert isinstance(link, UnansweredAtFirst)

        async def main() -> None:
            async with app.run_test(size=(100, 30)) as pilot:
                await until(  # from before the console joined: only the snapshot has it
                    pilot,
                    lambda: "job_submitted" in [e.kind for _, e in app.model.events.after(0)],
                    "the show's recent history",
                )
                said = [e.message for _, e in app.model.events.after(0) if e.kind == "console"]
                assert len(said) == 1 and "no snapshot from the orchestrator yet" in said[0]
                assert link.lost >= 1

        asyncio.run(main())


class FinalsLost(ConsoleLink):
    """A link that loses every ``jobs/<id>`` message of a finished job (as across a
    reconnection); the orchestrator's ``fleet`` publications and snapshot answers arrive."""

    def start(self, deliver: Any) -> None:
        def losing(item: Any) -> None:
            if not (isinstance(item, JobState) and item.state in FINAL_JOB_STATES):
                deliver(item)

        super().start(losing)


def test_a_job_whose_end_was_not_heard_is_shown_ended_from_the_orchestrators_snapshot(
    tmp_path: Path,
) -> None:
    with console_after_a_submission(tmp_path, FinalsLost) as (app, job_id):

        async def main() -> None:
            async with app.run_test(size=(100, 30)) as pilot:
                await until(pilot, lambda: app.model.job(job_id) is not None, "the job")
                app.send(OperatorCommand(command="cancel", job_id=job_id))
                await until(  # its "cancelled" message was lost; the fleet leaves it out
                    pilot,
                    lambda: getattr(app.model.job(job_id), "state", None) == "cancelled",
                    "the job cancelled",
                )

        asyncio.run(main())


def test_console_holds_releases_rejects_with_reason_and_reprioritises(tmp_path: Path) -> None:
    """Issue 14 against the real orchestrator: a landed vehicle stays held through ``p`` ``p``
    until released, a rejection carries the typed reason and reads ``rejected``, ``+`` raises."""
    show = moderated_show(tmp_path)
    keys = ShowKeys(show.show_id)
    vid = show.vehicles[0].id
    with Orchestrator(show), open_session(show.zenoh, role="client") as session:
        job_ids = []
        for text in ("永", "山"):
            request = SubmitRequest(text=text, client_id="test")
            reply = query_one(session, keys.submit, request, SubmitReply, timeout_s=10.0)
            assert reply.ok, reply
            job_ids.append(reply.job_id)
        app = ConsoleApp(settings_from_show(show), link=ConsoleLink(session, keys))

        def held() -> bool:
            return app._fleet.cell_text(vid, "state") in ("lost held", "idle held")

        async def scenario(pilot: Any) -> None:
            await until(pilot, lambda: app._queue.row_count == 2, "the submissions")
            app._queue.focus()
            for _ in range(2):  # the cursor stays on the job it was on when the rows came
                if app._queue.selected_job != job_ids[0]:
                    await pilot.press("up")
            await until(pilot, lambda: app._queue.selected_job == job_ids[0], "j0 chosen")
            await until(  # from before the console joined: only the snapshot has them
                pilot,
                lambda: [e.kind for _, e in app.model.events.after(0)].count("job_submitted") == 2,
                "the show's recent history",
            )
            app._queue.focus()
            await pilot.press("plus")
            await until(pilot, lambda: app.model.job(job_ids[0]).priority == 1, "priority 1")
            await until(pilot, lambda: app._queue.selected_job == job_ids[0], "j0 still chosen")
            await pilot.press("r", *"too rude", "enter")
            await until(
                pilot, lambda: app.model.job(job_ids[0]).state == "rejected", "the rejection"
            )
            error = app.model.job(job_ids[0]).error
            assert error is not None and error.message == "too rude"
            await until(
                pilot, lambda: str(app._queue.get_row(job_ids[0])[0]) == "rejected", "rejected"
            )
            app._fleet.focus()
            app._fleet.cursor_row = 0
            await pilot.press("l", "y")
            await until(pilot, held, f"{vid} held in the fleet table")
            await pilot.press("p")
            await until(pilot, lambda: app._header.queue_paused, "the queue paused")
            await pilot.press("p")
            await until(pilot, lambda: not app._header.queue_paused, "the queue resumed")
            await pilot.pause(0.5)
            assert held(), "resuming the queue released a held vehicle"
            app.send(clear_fault(vid))  # the wire shape of the console's reset
            await until(
                pilot,
                lambda: (
                    app.model.last_reply is not None
                    and app.model.last_reply[0].command == "clear_fault"
                ),
                "the orchestrator's answer to clear_fault",
            )
            assert app.model.last_reply is not None and app.model.last_reply[1].ok
            await pilot.press("u", "y")
            await until(pilot, lambda: not held(), f"{vid} released")
            app.send(OperatorCommand(command="fresh_sheet", board_id="b1"))  # the wire shape
            await until(
                pilot,
                lambda: (
                    app.model.last_reply is not None
                    and app.model.last_reply[0].command == "fresh_sheet"
                ),
                "the orchestrator's answer to fresh_sheet",
            )
            error = app.model.last_reply[1].error
            assert error is not None and error.code == "bad_state"  # understood: b1 is clean

        async def main() -> None:
            async with app.run_test(size=(120, 40)) as pilot:
                await scenario(pilot)

        asyncio.run(main())
