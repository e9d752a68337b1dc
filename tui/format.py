"""How values read on screen: short, unit-bearing, and the same in every view. Pure."""

from __future__ import annotations

import time

from rich.text import Text

from bus.messages import JobState
from tui.rows import QueueRow, VehicleRow
from tui.safe_text import clean

STATE_STYLES = {
    "idle": "green",
    "taking_off": "cyan",
    "writing": "bold #00d7ff",
    "returning": "cyan",
    "landing": "cyan",
    "landed": "green",
    "fault": "bold red",
    "lost": "bold white on red",
    "battery_swap": "bold black on yellow",
    "unknown": "dim",
}
"""Style of each vehicle state name."""

SECTION_LABELS = {
    "awaiting": ("approve?", "bold black on yellow"),
    "queued": ("queued", "cyan"),
    "active": ("active", "bold #00d7ff"),
    "done": ("done", "green"),
    "failed": ("failed", "bold red"),
}
"""Label and style of each queue section."""
ENDED_LABELS = {"rejected": ("rejected", "magenta"), "cancelled": ("cancelled", "dim")}
"""Label and style of jobs in the ``failed`` section that did not fail: the operator ended them."""
DETAIL_CHARS = 48
"""Longest detail of a job in the queue, in characters."""


def state_text(state: str) -> Text:
    """A vehicle state as a coloured word (``taking_off`` reads ``taking off``)."""
    return Text(clean(state.replace("_", " "), 20), style=STATE_STYLES.get(state, ""))


def duration(seconds: float | None) -> str:
    """``45s``, ``2m05s``, ``1h03m``; ``-`` when unknown."""
    if seconds is None:
        return "-"
    s = max(0, round(seconds))
    if s < 60:
        return f"{s}s"
    if s < 3600:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s // 3600}h{(s % 3600) // 60:02d}m"


def link_age(row: VehicleRow) -> Text:
    """Seconds since the vehicle was last heard from (``<1s`` when fresh); red when stale."""
    if row.link_age_s is None:
        return Text("-", style="dim")
    age = row.link_age_s
    shown = "<1s" if age < 1 else f"{age:.1f}s" if age < 10 else duration(age)
    return Text(shown, style="bold red" if row.stale or row.state == "lost" else "")


def link(row: VehicleRow) -> Text:
    """Link quality: :func:`link_age`, then the share of its autopilot's messages lost when it
    has an autopilot link (``<1s 2%``); yellow from 1 % lost, red from 5 %."""
    age = link_age(row)
    loss = row.link_loss_fraction
    if loss is None:
        return age
    style = "bold red" if loss >= 0.05 else "yellow" if loss >= 0.01 else age.style
    return Text(f"{age.plain} {100 * loss:.0f}%", style=style)


def preflight(row: VehicleRow, *, full: bool = False) -> Text:
    """``ok``, or what holds it on the ground: the failing check's name (``✗ mocap``), the
    whole reason with ``full``; ``-`` while it is away or unknown."""
    if row.state in ("lost", "unknown"):
        return Text("-", style="dim")
    if not row.preflight:
        return Text("ok", style="green")
    if full:
        return Text(f"✗ {row.preflight}", style="bold yellow")
    check, colon, _ = row.preflight.partition(":")
    named = colon and check.isalpha() and check.islower() and len(check) <= 9
    return Text(f"✗ {check if named else 'pre-arm'}", style="bold yellow")


def tracking_error(row: VehicleRow) -> Text:
    """Tracking error in centimetres; reversed red above the show's threshold."""
    if row.tracking_error_m is None:
        return Text("-", style="dim")
    return Text(
        f"{100 * row.tracking_error_m:.1f}cm",
        style="bold white on red" if row.over_threshold else "",
    )


def force(row: VehicleRow) -> Text:
    """Contact force against its target, ``4.8/5.0N``; reversed red when off by more than the
    console's margin while writing; ``-`` for a kind that senses no force."""
    if row.force_n is None:
        return Text("-", style="dim")
    shown = f"{row.force_n:.1f}"
    if row.force_reference_n is not None:
        shown += f"/{row.force_reference_n:.1f}"
    return Text(shown + "N", style="bold white on red" if row.force_off else "")


def force_detail(row: VehicleRow) -> Text:
    """``4.82 N, target 5.00 N`` for the detail view; ``-`` without force."""
    if row.force_n is None:
        return Text("-", style="dim")
    text = f"{row.force_n:.2f} N"
    if row.force_reference_n is not None:
        text += f", target {row.force_reference_n:.2f} N"
    return Text(text, style="bold white on red" if row.force_off else "")


def battery(fraction: float | None, minutes_left: float | None = None) -> Text:
    """Battery in percent and, when known, minutes left (``73% 12m``); yellow under 30 %, red
    under 15 %."""
    if fraction is None:
        return Text("-", style="dim")
    style = "bold red" if fraction < 0.15 else "yellow" if fraction < 0.30 else ""
    minutes = "" if minutes_left is None else f" {minutes_left:.0f}m"
    return Text(f"{100 * fraction:.0f}%{minutes}", style=style)


def progress(fraction: float, width: int = 6) -> str:
    """A small bar and a percentage, e.g. ``███░░░ 50%``."""
    fraction = min(1.0, max(0.0, fraction))
    full = round(fraction * width)
    return "█" * full + "░" * (width - full) + f" {100 * fraction:3.0f}%"


def clock(time_s: float) -> str:
    """Local wall-clock time ``HH:MM:SS`` of a Unix time."""
    return time.strftime("%H:%M:%S", time.localtime(time_s))


def job_detail(row: QueueRow) -> str:
    """The one thing to know about a job in its section (bus strings cleaned: plain text)."""
    job = row.job
    if row.section == "awaiting":
        return f"from {clean(job.client_id, DETAIL_CHARS - 5)}"
    if row.section == "queued":
        position = f"#{job.queue_position}" if job.queue_position is not None else "#?"
        return f"{position} ETA {duration(job.eta_s)}"
    if row.section == "active":
        return f"{short_id(job.vehicle_id or '?', 16)} {100 * job.progress:.0f}%"
    if row.section == "done":
        return metrics_text(job)
    reason = (job.error.message if job.error is not None else "") or job.state
    if job.state == "cancelled" and job.metrics is not None:  # what its vehicle had written
        reason = f"{job.metrics.flown_fraction:.0%} written; {reason}"
    return clean(reason, DETAIL_CHARS)


def metrics_text(job: JobState) -> str:
    """``RMSE 1.2cm IoU 0.84`` of a finished job: ``-`` for what was not measured (a pen that
    never came down, a backend that does not know its brush), ``partial 30%`` after a job
    written in part."""
    m = job.metrics
    if m is None:
        return "no metrics"
    iou = "-" if m.iou is None else f"{m.iou:.2f}"
    rmse = "-" if m.rmse_pen_down_m is None else f"{100 * m.rmse_pen_down_m:.1f}cm"
    partial = f" partial {m.flown_fraction:.0%}" if m.flown_fraction < 1.0 else ""
    return f"RMSE {rmse} IoU {iou}{partial}"


def section_text(row: QueueRow) -> Text:
    label, style = SECTION_LABELS[row.section]
    if row.section == "failed":
        label, style = ENDED_LABELS.get(row.job.state, (label, style))
    return Text(label, style=style)


def vehicle_state_text(state: str, held: bool, paused: bool = False) -> Text:
    """:func:`state_text`, marked ``held`` when the operator holds the vehicle on the ground,
    ``paused`` when it takes no new job."""
    text = state_text(state)
    if held:
        text.append(" held", style="bold black on yellow")
    elif paused:
        text.append(" paused", style="bold black on cyan")
    return text


def short_id(identifier: str, width: int = 8) -> str:
    """An identifier (or label) from the bus, cleaned and cut to ``width`` characters."""
    return clean(identifier, width)


def job_totals_text(job_counts: dict[str, int]) -> str:
    """``; 612 done, 3 failed`` from the orchestrator's job counts; empty before any count."""
    if not job_counts:
        return ""
    done, failed = job_counts.get("done", 0), job_counts.get("failed", 0)
    return f"; {done} done" + (f", {failed} failed" if failed else "")
