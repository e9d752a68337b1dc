"""The alert line at 80 columns: the first alert is always readable, cut to fit."""

from __future__ import annotations

from tui.widgets.alert_bar import alert_line

LONG = "uav3 is lost: silent for 2.1 s although its token remains; its job 永 waits for it" * 2


def test_a_long_first_alert_is_cut_to_fit_not_dropped() -> None:
    line = alert_line((LONG, "b2 half-written by 光", "uav1 fault: estop"), 80)
    assert line.cell_len <= 80
    assert "uav3 is lost: silent for 2.1 s" in line.plain and line.plain.endswith("+2 more")
    assert "…" in line.plain


def test_whole_alerts_while_they_fit_then_a_count() -> None:
    line = alert_line(("b2 half-written by 光", "uav1 fault: estop", LONG), 80)
    assert "b2 half-written by 光 │ uav1 fault: estop │ +1 more" in line.plain
    assert line.cell_len <= 80
    assert alert_line(("uav1 fault: estop",), 80).plain == " ⚠ 1  x:ack uav1 fault: estop"
