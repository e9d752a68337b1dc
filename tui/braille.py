"""A small braille canvas: 2x4 dots per terminal cell, layered so that each cell takes one colour.

Pure: no Textual, no I/O. Dot coordinates grow right (x) and DOWN (y); one terminal cell holds
dots ``x in [2c, 2c+1]`` and ``y in [4r, 4r+3]``. Because a terminal cell is about twice as tall as
it is wide, braille dots are close to square, so one scale for x and y keeps shapes undistorted.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from rich.style import Style
from rich.text import Text

BRAILLE_BASE = 0x2800
"""Code point of the empty braille pattern."""

_DOT_BITS = ((0x01, 0x08), (0x02, 0x10), (0x04, 0x20), (0x40, 0x80))
"""``_DOT_BITS[row][col]``: bit of dot (col, row) inside one cell (Unicode braille numbering)."""


class BrailleCanvas:
    """Layers of braille dots; the highest layer with a dot in a cell gives the cell its style.

    Layer 0 has the lowest priority. Drawing outside the canvas is silently clipped (a vehicle
    taking off from beside its board flies off the picture; that is not an error).
    """

    def __init__(self, cols: int, rows: int, layers: int = 1) -> None:
        if cols < 1 or rows < 1 or layers < 1:
            raise ValueError(f"canvas needs cols, rows, layers >= 1, got {cols}, {rows}, {layers}")
        self.cols = cols
        """Width in terminal cells."""
        self.rows = rows
        """Height in terminal cells."""
        self._bits = [bytearray(cols * rows) for _ in range(layers)]
        self.dirty_rows: set[int] = set(range(rows))
        """Rows changed since the owner last emptied this set (for views that cache rows)."""

    @property
    def width_dots(self) -> int:
        return 2 * self.cols

    @property
    def height_dots(self) -> int:
        return 4 * self.rows

    @property
    def layers(self) -> int:
        return len(self._bits)

    def clear(self) -> None:
        for bits in self._bits:
            bits[:] = bytes(len(bits))
        self.dirty_rows.update(range(self.rows))

    def clear_layer(self, layer: int) -> None:
        bits = self._bits[layer]
        for r in range(self.rows):
            if any(bits[r * self.cols : (r + 1) * self.cols]):
                self.dirty_rows.add(r)
        bits[:] = bytes(len(bits))

    def set(self, x: int, y: int, layer: int = 0) -> None:
        """Turn on dot (x, y) in ``layer``; ignored outside the canvas (integer dots only)."""
        if 0 <= x < 2 * self.cols and 0 <= y < 4 * self.rows:
            self._bits[layer][(y >> 2) * self.cols + (x >> 1)] |= _DOT_BITS[y & 3][x & 1]
            self.dirty_rows.add(y >> 2)

    def get(self, x: int, y: int, layer: int | None = None) -> bool:
        """Whether dot (x, y) is on in ``layer`` (any layer when None)."""
        if not (0 <= x < 2 * self.cols and 0 <= y < 4 * self.rows):
            return False
        index = (y >> 2) * self.cols + (x >> 1)
        bit = _DOT_BITS[y & 3][x & 1]
        layers = self._bits if layer is None else [self._bits[layer]]
        return any(bits[index] & bit for bits in layers)

    def line(self, x0: float, y0: float, x1: float, y1: float, layer: int = 0) -> None:
        """Dots along the segment from (x0, y0) to (x1, y1), both ends included when visible."""
        if not all(math.isfinite(v) for v in (x0, y0, x1, y1)):
            return
        clipped = clip_segment(x0, y0, x1, y1, self.width_dots - 0.5, self.height_dots - 0.5)
        if clipped is None:
            return
        ix0, iy0, ix1, iy1 = (round(v) for v in clipped)
        steps = max(abs(ix1 - ix0), abs(iy1 - iy0))
        if steps == 0:
            self.set(ix0, iy0, layer)
            return
        dx = (ix1 - ix0) / steps
        dy = (iy1 - iy0) / steps
        for i in range(steps + 1):
            self.set(round(ix0 + dx * i), round(iy0 + dy * i), layer)

    def polyline(self, points: Sequence[tuple[float, float]], layer: int = 0) -> None:
        """Connected segments through ``points`` (a single point draws one dot)."""
        if len(points) == 1:
            self.set(round(points[0][0]), round(points[0][1]), layer)
        for (xa, ya), (xb, yb) in itertools.pairwise(points):
            self.line(xa, ya, xb, yb, layer)

    def cell(self, col: int, row: int) -> tuple[str, int | None]:
        """The character of one cell and the layer that colours it (None when empty)."""
        index = row * self.cols + col
        combined = 0
        top: int | None = None
        for layer, bits in enumerate(self._bits):
            if bits[index]:
                combined |= bits[index]
                top = layer
        if not combined:
            return " ", None
        return chr(BRAILLE_BASE + combined), top

    def row_runs(self, row: int) -> list[tuple[str, int | None]]:
        """One row as runs of characters sharing a colouring layer (None: empty cells)."""
        runs: list[tuple[str, int | None]] = []
        chars: list[str] = []
        run_layer: int | None = None
        for c in range(self.cols):
            char, layer = self.cell(c, row)
            if layer != run_layer and chars:
                runs.append(("".join(chars), run_layer))
                chars = []
            run_layer = layer
            chars.append(char)
        if chars:
            runs.append(("".join(chars), run_layer))
        return runs

    def lines(self) -> list[str]:
        """The canvas as plain text lines (no colours)."""
        return ["".join(self.cell(c, r)[0] for c in range(self.cols)) for r in range(self.rows)]

    def to_text(self, styles: Sequence[Style | str], background: Style | str = "") -> Text:
        """Rich text of the canvas, one style per layer; runs of equal style are merged."""
        text = Text(no_wrap=True, overflow="crop")
        for r in range(self.rows):
            for chars, layer in self.row_runs(r):
                text.append(chars, background if layer is None else styles[layer])
            if r < self.rows - 1:
                text.append("\n")
        return text


def clip_segment(
    x0: float, y0: float, x1: float, y1: float, x_max: float, y_max: float
) -> tuple[float, float, float, float] | None:
    """The part of a segment inside ``[-0.5, x_max] x [-0.5, y_max]`` (Liang-Barsky), or None."""
    t0, t1 = 0.0, 1.0
    dx, dy = x1 - x0, y1 - y0
    for p, q in ((-dx, x0 + 0.5), (dx, x_max - x0), (-dy, y0 + 0.5), (dy, y_max - y0)):
        if p == 0:
            if q < 0:
                return None
            continue
        t = q / p
        if p < 0:
            t0 = max(t0, t)
        else:
            t1 = min(t1, t)
        if t0 > t1:
            return None
    return x0 + t0 * dx, y0 + t0 * dy, x0 + t1 * dx, y0 + t1 * dy


def fit_transform(
    bounds: tuple[float, float, float, float],
    width_dots: int,
    height_dots: int,
    *,
    margin_dots: int = 1,
    y_up: bool = True,
) -> tuple[float, float, float, bool]:
    """Scale and offsets mapping a box ``(x_min, y_min, x_max, y_max)`` into a canvas, centred.

    Returns ``(scale, x_offset, y_offset, y_up)``; use with :func:`apply_transform`. One scale for
    both axes keeps shapes undistorted; a degenerate box (a dot, a straight line) is handled.
    """
    x_min, y_min, x_max, y_max = bounds
    span_x = max(x_max - x_min, 1e-12)
    span_y = max(y_max - y_min, 1e-12)
    usable_w = max(width_dots - 1 - 2 * margin_dots, 1)
    usable_h = max(height_dots - 1 - 2 * margin_dots, 1)
    scale = min(usable_w / span_x, usable_h / span_y)
    x_off = (width_dots - 1) / 2 - scale * (x_min + x_max) / 2
    y_off = (height_dots - 1) / 2 + (1 if y_up else -1) * scale * (y_min + y_max) / 2
    return scale, x_off, y_off, y_up


def apply_transform(
    transform: tuple[float, float, float, bool], x: float, y: float
) -> tuple[float, float]:
    """Dot coordinates of a point under a transform from :func:`fit_transform`."""
    scale, x_off, y_off, y_up = transform
    return x_off + scale * x, (y_off - scale * y) if y_up else (y_off + scale * y)
