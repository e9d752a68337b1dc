"""What ``skyquill plan`` and ``skyquill fly`` share: the text or strokes file to write, the
writing area it is laid out in, and how a bad value of either is told (one line, exit 2).

Sizing rule, the same for both commands and for a show's jobs (``vehicles.jobs.lay_out``): the
character is scaled, aspect kept, to the largest size inside ``--width`` x ``--height`` less
``--margin`` on every side. A box, not a height alone: a glyph without a drawing frame (一 is one
flat stroke) fitted by its ink height alone would come out metres wide; in a box it is as wide
as the box. Kept light (no numpy): ``plan``'s imports are counted (tests/test_cli_imports.py).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from planner import defaults

AREA_WIDTH_M = 1.0
"""Default width in [m] of the writing area of ``plan`` and ``fly``."""
AREA_HEIGHT_M = 1.0
"""Default height in [m] of the writing area of ``plan`` and ``fly``."""
WALL_CENTRE_HEIGHT_M = 1.5
"""Height in [m] of the writing area's centre on a wall (the floor and boards: their surface)."""


def bounded(
    low: float, high: float = math.inf, *, unit: str = "", open_low: bool = False
) -> Callable[[str], float]:
    """An argparse ``type``: a float in ``[low, high]`` (``(low, high]`` with ``open_low``),
    else the flag's one-line error saying the range."""
    shown = f" {unit}" if unit else ""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        too_low = value <= low if open_low else value < low
        if not math.isfinite(value) or too_low or value > high:
            lo = f"above {low:g}" if open_low else f"at least {low:g}"
            hi = f" and at most {high:g}" if math.isfinite(high) else ""
            raise argparse.ArgumentTypeError(f"must be {lo}{hi}{shown}, not {text}")
        return value

    return parse


POSITIVE_M = bounded(0.0, unit="m", open_low=True)
"""A length in [m] above 0."""


def add_source_arguments(parser: argparse.ArgumentParser) -> None:
    """``--strokes FILE`` or ``--text TEXT``, one of them."""
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--strokes", metavar="FILE", help="strokes JSON (docs/formats.md)")
    source.add_argument("--text", metavar="TEXT", help="Latin (Hershey) or Chinese text")


def add_area_arguments(parser: argparse.ArgumentParser) -> None:
    """The writing area the character is fitted into (the module's sizing rule)."""
    area = parser.add_argument_group(
        "writing area (the character fits inside width x height less the margin, as on a "
        "show's board)"
    )
    area.add_argument(
        "--width", type=POSITIVE_M, default=AREA_WIDTH_M, help=f"area width [m] ({AREA_WIDTH_M})"
    )
    area.add_argument(
        "--height",
        type=POSITIVE_M,
        default=AREA_HEIGHT_M,
        help=f"area height [m] ({AREA_HEIGHT_M})",
    )
    area.add_argument(
        "--margin",
        type=bounded(0.0, unit="m"),
        default=defaults.MARGIN_M,
        help=f"margin kept free inside the area [m] ({defaults.MARGIN_M})",
    )


def area_of(args: argparse.Namespace) -> tuple[float, float]:
    """(width, height) in [m] of the writing area."""
    return (args.width, args.height)


def source_of(args: argparse.Namespace) -> str:
    """What errors name as the input: the strokes file, or ``<text>``."""
    return str(args.strokes) if args.strokes is not None else "<text>"


def read_glyph(args: argparse.Namespace) -> Any:
    """The glyph of ``--strokes`` or ``--text``: ValueError ``cannot read: ...`` for a file that
    cannot be read, PlannerError naming the stroke and point of a bad one."""
    from planner.glyphs import parse_strokes_json, text_glyph

    if args.strokes is None:
        return text_glyph(args.text)
    try:
        text = Path(args.strokes).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"cannot read: {exc}") from None
    return parse_strokes_json(text, source_name=args.strokes)


def ink_size_m(glyph: Any) -> list[float]:
    """Width and height in [m] of a laid-out glyph's ink."""
    x_min, y_min, x_max, y_max = glyph.bounds()
    return [float(x_max - x_min), float(y_max - y_min)]


AREA_FLAGS = {"width_m": "--width", "height_m": "--height", "margin_m": "--margin"}
"""The layout's fields (``planner.glyphs.layout``) and the flags that set them."""


def print_error(prog: str, source: str, exc: Exception) -> int:
    """One line on stderr naming ``source`` and, for a PlannerError, its stroke and point, or
    the flag (else the field) at fault; the exit status 2."""
    from planner.errors import PlannerError

    where = [source]
    message = str(exc)
    if isinstance(exc, PlannerError):
        message = exc.message.removeprefix(f"{source}: ")
        if exc.stroke_index is not None:
            where.append(f"stroke {exc.stroke_index}")
        if exc.point_index is not None:
            where.append(f"point {exc.point_index}")
        if exc.stroke_index is None and exc.field is not None:
            flag = AREA_FLAGS.get(exc.field)
            where.append(flag if flag is not None else f"field {exc.field!r}")
    location = ", ".join(where[1:])
    prefix = f"{source}: {location}" if location else source
    print(f"{prog}: error: {prefix}: {message}", file=sys.stderr)
    return 2


def cannot_write(prog: str, exc: OSError) -> int:
    """An output file that cannot be written, in one line (exit status 2)."""
    print(f"{prog}: error: cannot write {exc.filename}: {exc.strerror or exc}", file=sys.stderr)
    return 2
