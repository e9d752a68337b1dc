"""One voice for every command's human summary: numbers to three significant digits with their
unit (lengths under 10 cm in millimetres), the character itself, and a verdict in words
(``feasible: yes``, ``within bounds``, ``ABORTED``). ``--json`` prints the same facts for
programs. Pure and light: no numpy (``status`` and ``plan`` count their imports)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

UNITS = {
    "m": "m",
    "s": "s",
    "mps": "m/s",
    "mps2": "m/s^2",
    "n": "N",
    "nps": "N/s",
    "radps": "rad/s",
}
"""Unit suffixes of the project's names (``_mps2``) and how a person reads them."""


def printable(text: str) -> str:
    """``text`` safe for a terminal: a character that is not printable (an escape sequence,
    a direction override) shown as ``U+XXXX``; a label may come from anyone."""
    return "".join(c if c.isprintable() else f"U+{ord(c):04X}" for c in text)


def sig(value: float | None, digits: int = 3) -> str:
    """``value`` to ``digits`` significant digits, never in exponent notation, trailing zeros
    dropped (``0.3``, ``18``, ``2.13``); ``-`` for None or NaN (not measured)."""
    if value is None or not math.isfinite(value):
        return "-"
    rounded = float(f"{value:.{digits - 1}e}")  # 9.996 -> 10.0 before the decimals are chosen
    if rounded == 0.0:
        return "0"
    decimals = max(digits - 1 - math.floor(math.log10(abs(rounded))), 0)
    text = f"{rounded:.{decimals}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def ratio(value: float | None) -> str:
    """A ratio between 0 and 1 (an IoU) to two decimals; ``-`` when not measured."""
    if value is None or not math.isfinite(value):
        return "-"
    return f"{value:.2f}"


def length(value_m: float | None) -> str:
    """A length: millimetres under 0.1 m (``2.13 mm``), metres above (``0.95 m``)."""
    if value_m is None or not math.isfinite(value_m):
        return "not measured"
    if abs(value_m) < 0.1:
        return f"{sig(value_m * 1e3)} mm"
    return f"{sig(value_m)} m"


def seconds(value_s: float | None) -> str:
    """A time in [s], three significant digits."""
    return f"{sig(value_s)} s"


def numbers(value: Any) -> str:
    """A number or a list of numbers, :func:`sig` each, comma separated."""
    if isinstance(value, list | tuple):
        return ", ".join(sig(float(v)) for v in value)
    return sig(float(value))


def unit_of(name: str) -> str:
    """How a person reads the unit suffix of a field's name (``peak_speed_mps``: m/s)."""
    return UNITS.get(name.rsplit("_", 1)[-1], "")


def peak_limit_pairs(feasibility: Mapping[str, Any]) -> list[tuple[str, str]]:
    """(peak, limit) field pairs of a kind's feasibility report, by the kinds' naming: a peak
    ``peak_<quantity>_<unit>`` and the one limit ``<name>_max_<unit>`` of the same unit
    (``peak_speed_mps`` and ``v_max_mps``); a peak with no such limit, or two, is left out."""
    pairs = []
    for peak in feasibility:
        if not peak.startswith("peak_"):
            continue
        unit = peak.rsplit("_", 1)[-1]
        limits = [k for k in feasibility if k.endswith(f"_max_{unit}")]
        if len(limits) == 1:
            pairs.append((peak, limits[0]))
    return pairs


def _within(peak: Any, limit: Any) -> bool:
    peaks = peak if isinstance(peak, list | tuple) else [peak]
    limits = limit if isinstance(limit, list | tuple) else [limit] * len(peaks)
    return all(
        float(p) <= float(q) * (1.0 + 1e-3) + 1e-9 for p, q in zip(peaks, limits, strict=False)
    )


def feasible(feasibility: Mapping[str, Any]) -> bool:
    """Whether a kind's plan keeps its limits: its own ``feasible`` when it says, else every
    peak within its limit (:func:`peak_limit_pairs`, 0.1 % for round-off)."""
    own = feasibility.get("feasible")
    if isinstance(own, bool):
        return own
    return all(_within(feasibility[p], feasibility[q]) for p, q in peak_limit_pairs(feasibility))


def limits_line(feasibility: Mapping[str, Any]) -> str:
    """``speed 0.169 of 0.2 m/s; accel 0.243, 0.146 of 0.25, 0.15 m/s^2``: each peak against
    its limit."""
    parts = []
    for peak, limit in peak_limit_pairs(feasibility):
        quantity = peak.removeprefix("peak_").rsplit("_", 1)[0].replace("_", " ")
        parts.append(
            f"{quantity} {numbers(feasibility[peak])} of {numbers(feasibility[limit])}"
            f" {unit_of(limit)}".rstrip()
        )
    return "; ".join(parts)


def yes_no(flag: bool) -> str:
    return "yes" if flag else "no"


def size(size_m: Sequence[float]) -> str:
    """``0.9 x 0.0698 m``: a width and a height, in metres both."""
    return " x ".join(sig(v) for v in size_m) + " m"


def plan_headline(
    label: str, kind: str, size_m: Sequence[float], duration_s: float, strokes: int, ok: bool
) -> str:
    """The first line of every plan summary (``ok``: feasible)."""
    noun = "stroke" if strokes == 1 else "strokes"
    return (
        f"{printable(label)} for {kind}: {size(size_m)}, {seconds(duration_s)} to write, "
        f"{strokes} {noun}; feasible: {yes_no(ok)}"
    )


def flight_lines(doc: Mapping[str, Any]) -> list[str]:
    """The human summary of a flight's metrics document (what ``fly --json`` prints)."""
    label, kind = printable(doc["label"]), doc["kind"]
    sim_s, wall_s = doc["sim_time_s"], doc["wall_time_s"]
    bounds = doc["bounds"]
    if doc["aborted"] is not None:
        wrote = "some ink, not counted" if doc["wrote_ink"] else "nothing written"
        head = f"{label} by {kind}: ABORTED at {seconds(sim_s)} simulated, {wrote}: ink IoU 0"
        verdict = f"  {doc['aborted']}"
    elif not doc["wrote_ink"]:
        head = f"{label} by {kind}: nothing written: ink IoU 0"
        verdict = "  out of bounds"
    else:
        words = "within bounds" if doc["within_bounds"] else "OUT OF BOUNDS"
        head = f"{label} by {kind}: written, {words}: ink IoU {ratio(doc['iou'])}"
        verdict = (
            f"  bounds: pen-down RMSE at most {length(bounds['rmse_pen_down_max_m'])}, "
            f"ink IoU at least {ratio(bounds['iou_min'])}"
        )
    pen = doc["rmse_pen_down_m"]
    pen_text = length(pen) if pen is not None else "not measured (the pen never came down)"
    errors = (
        f"  pen-down RMSE {pen_text}; whole-run RMSE {length(doc['rmse_m'])}, "
        f"max error {length(doc['max_error_m'])}"
    )
    rtf = doc.get("real_time_factor")
    speed = f" ({sig(rtf, 2)}x real time)" if rtf else ""
    times = (
        f"  {size(doc['planned_ink_size_m'])} of ink planned; {seconds(sim_s)} simulated of "
        f"{seconds(doc['planned_duration_s'])} planned, "
        f"{seconds(wall_s)} wall{speed}, seed {doc['seed']}"
    )
    return [head, verdict, errors, times]
