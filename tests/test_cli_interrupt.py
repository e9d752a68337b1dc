"""Ctrl-C in ``skyquill up``'s terminal (``cli/interrupt.py``): asks when vehicles fly."""

from __future__ import annotations

from cli.interrupt import CONFIRM_WINDOW_S, StopRequests


class Clock:
    def __init__(self) -> None:
        self.now_s = 100.0

    def __call__(self) -> float:
        return self.now_s


def _requests(flying: list[str] | None) -> tuple[StopRequests, list[str], Clock]:
    said: list[str] = []
    clock = Clock()
    return StopRequests(lambda: flying, said.append, "show.yaml", clock), said, clock


def test_ctrl_c_with_nothing_in_the_air_stops_at_once() -> None:
    stop, said, _ = _requests([])
    assert not stop.due()
    stop.interrupt()
    assert stop.due() and said == []


def test_ctrl_c_with_vehicles_in_the_air_names_them_and_a_second_one_stops() -> None:
    stop, said, clock = _requests(["uav1", "uav3"])
    stop.interrupt()
    assert not stop.due() and not stop.due()  # asked once, then it keeps running
    assert said == [said[0]] and said[0].startswith("uav1, uav3 are in the air.")
    assert "lands them and stops the show" in said[0] and "skyquill down show.yaml" in said[0]
    clock.now_s += CONFIRM_WINDOW_S - 1.0
    stop.interrupt()
    assert stop.due()


def test_a_second_ctrl_c_long_after_the_question_asks_again() -> None:
    stop, said, clock = _requests(["uav2"])
    stop.interrupt()
    assert not stop.due()
    clock.now_s += CONFIRM_WINDOW_S + 1.0
    stop.interrupt()
    assert not stop.due() and len(said) == 2 and said[1].startswith("uav2 is in the air.")


def test_without_an_answer_it_asks_and_sigterm_never_asks() -> None:
    stop, said, _ = _requests(None)
    stop.interrupt()
    assert not stop.due() and "the orchestrator does not answer" in said[0]
    stop.terminate()
    assert stop.due()
