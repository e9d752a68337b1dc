"""From board-local strokes to one continuous 3-D data path with pen up/down (section 4-5).

For every stroke: approach point above its start (writing height + clearance), its turning points
at writing height (pen down), a lift point above its end; between strokes a straight pen-up travel.
Long straight pieces are densified with extra (lighter) data points so the regression keeps them
straight. At sharp corners (turning by more than 60 degrees) the brush pauses briefly (a repeated
data point, 0.1 s) and extra points 2 cm before and after the corner keep it from overshooting.
The vertical hop between writing height and pen-up height (approach and lift) is split into at
least three pieces whatever the clearance: its intermediate points, directly above the stroke
end, hold the brush there while it sinks or rises. Without them a low hop (clearance <= the
densify spacing) is one plain segment, the brush reaches the stroke end at speed and slides on
past it (or arrives sideways) while still within the pen-contact height: a smear of 2-6 cm.
The initial time of each leg (turning point to turning point, or to a corner's extra point) is
``max(d / v_nom, 2 sqrt(d / a_nom), t_min)`` -- rest-to-rest time with nominal speed and
acceleration -- spread over its densified pieces in proportion to length.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from planner.board import BoardFrame
from planner.errors import PlannerError
from planner.turning_points import split_and_merge

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

KIND_PEN_UP = 0
"""Approach / lift point above a stroke end."""
KIND_TURNING = 1
"""A turning point at writing height (pen down)."""
KIND_DENSE = 2
"""Extra point on a straight piece of a stroke (pen down)."""
KIND_TRAVEL = 3
"""Extra point on a pen-up travel between strokes."""
KIND_HOP = 4
"""Extra point on the vertical hop above a stroke end (approach / lift)."""


@dataclass(frozen=True)
class PathSettings:
    """Geometry and weighting of the data path."""

    write_height_m: float
    """Height of the vehicle reference above the board surface while writing, [m]."""
    clearance_m: float
    """Extra height with the pen up, [m]."""
    split_threshold_m: float
    """Split-and-merge distance threshold, [m]."""
    densify_spacing_m: float
    """Largest spacing of data points along straight pieces, [m]."""
    nominal_speed_mps: float
    """Cruise speed of the initial time allocation, [m/s]."""
    nominal_accel_mps2: float
    """Acceleration of the initial time allocation, [m/s^2]."""
    min_leg_time_s: float = 0.2
    """Shortest time given to one leg, [s]."""
    weight_turning: float = 2.0
    """Weight of turning points (and approach/lift points)."""
    weight_dense: float = 0.5
    """Weight of densified stroke points."""
    weight_travel: float = 0.1
    """Weight of densified travel points."""
    corner_angle_deg: float = 60.0
    """A turning point where the direction turns by more than this is a sharp corner."""
    corner_dwell_s: float = 0.1
    """Initial time the brush rests on a sharp corner (a repeated data point), [s]."""
    corner_offset_m: float = 0.02
    """Extra data points this far before and after a sharp corner along its legs, [m]."""
    hop_pieces: int = 3
    """Least number of pieces of each vertical hop (approach / lift), whatever the clearance."""
    weight_hop: float = 2.0
    """Weight of the intermediate hop points (they keep the brush above the stroke end; at
    0.5 a 2 cm hop flown at the limits let the brush run on 9 mm past the end, at 2.0 3.5 mm)."""


@dataclass(frozen=True, eq=False)
class WritingPath:
    """Data points of one character, world ENU, with their initial time allocation."""

    points_m_enu: FloatArray
    """Data points in [m], shape (N, 3)."""
    weights: FloatArray
    """Regression weight per point, shape (N,)."""
    kinds: IntArray
    """``KIND_*`` code per point, shape (N,)."""
    stroke_of_point: IntArray
    """Stroke index per point, -1 for travel/pen-up points, shape (N,)."""
    segment_durations_s: FloatArray
    """Initial ``T_i`` between consecutive points in [s], shape (N - 1,)."""
    stroke_ranges: tuple[tuple[int, int], ...]
    """Per stroke: indices of its first and last point at writing height."""
    pen_windows: tuple[tuple[int, int], ...]
    """Per stroke: indices of its approach point and its lift point (the brush may touch the
    board only between them)."""
    turning_points_board_m: tuple[FloatArray, ...]
    """Per stroke: turning points in board-local [m], shape (k, 2)."""
    write_z_m: float
    """World z of the reference while writing, [m]."""


def validate_strokes(strokes_board_m: Sequence[FloatArray]) -> list[FloatArray]:
    """Arrays (n_i, 2) of finite floats with >= 2 distinct points; repeats are dropped."""
    if len(strokes_board_m) == 0:
        raise PlannerError("no strokes to write", field="strokes")
    clean = []
    for k, stroke in enumerate(strokes_board_m):
        arr = np.asarray(stroke, dtype=np.float64)
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise PlannerError(f"expected (n, 2) points, got shape {arr.shape}", stroke_index=k)
        bad = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        if bad.size:
            raise PlannerError(
                "coordinate is not a finite number", stroke_index=k, point_index=int(bad[0])
            )
        keep = np.concatenate([[True], np.any(np.diff(arr, axis=0) != 0.0, axis=1)])
        arr = arr[keep]
        if arr.shape[0] < 2:
            raise PlannerError("needs at least two distinct points", stroke_index=k)
        clean.append(arr)
    return clean


def _leg_time(distance: float, s: PathSettings) -> float:
    return max(
        distance / s.nominal_speed_mps,
        2.0 * math.sqrt(distance / s.nominal_accel_mps2),
        s.min_leg_time_s,
    )


class _Builder:
    def __init__(self, settings: PathSettings) -> None:
        self.s = settings
        self.points: list[FloatArray] = []
        self.weights: list[float] = []
        self.kinds: list[int] = []
        self.strokes: list[int] = []
        self.durations: list[float] = []

    def start(self, p: FloatArray, kind: int, stroke: int) -> None:
        self._append(p, kind, stroke, self.s.weight_turning)

    def _append(self, p: FloatArray, kind: int, stroke: int, weight: float) -> None:
        self.points.append(p)
        self.kinds.append(kind)
        self.strokes.append(stroke)
        self.weights.append(weight)

    def leg(
        self,
        p: FloatArray,
        kind: int,
        stroke: int,
        extra_kind: int,
        extra_w: float,
        end_w: float | None = None,
    ) -> None:
        """Straight leg from the last point to ``p``, densified, rest-to-rest nominal time."""
        a = self.points[-1]
        dist = float(np.linalg.norm(p - a))
        pieces = max(1, math.ceil(dist / self.s.densify_spacing_m - 1e-9))
        leg_time = _leg_time(dist, self.s)
        for j in range(1, pieces):
            self._append(a + (p - a) * (j / pieces), extra_kind, stroke, extra_w)
        self._append(p, kind, stroke, self.s.weight_turning if end_w is None else end_w)
        self.durations.extend([leg_time / pieces] * pieces)

    def hop(self, p: FloatArray, kind: int, stroke: int) -> None:
        """Vertical hop from the last point to ``p`` (approach or lift), >= ``hop_pieces``.

        Without clearance there is no hop: the last point takes the role of ``p``."""
        s = self.s
        a = self.points[-1]
        dist = float(np.linalg.norm(p - a))
        if dist == 0.0:
            if kind == KIND_TURNING:  # the approach point is the stroke's first point
                self.kinds[-1], self.strokes[-1], self.weights[-1] = kind, stroke, s.weight_turning
            return
        pieces = max(s.hop_pieces, math.ceil(dist / s.densify_spacing_m - 1e-9), 1)
        leg_time = _leg_time(dist, s)
        for j in range(1, pieces):
            self._append(a + (p - a) * (j / pieces), KIND_HOP, stroke, s.weight_hop)
        self._append(p, kind, stroke, s.weight_turning)
        self.durations.extend([leg_time / pieces] * pieces)

    def stroke_leg(self, p: FloatArray, stroke: int, from_corner: bool, to_corner: bool) -> None:
        """A pen-down leg; near sharp corners extra points keep the brush from overshooting."""
        s = self.s
        a = self.points[-1]
        dist = float(np.linalg.norm(p - a))
        if dist == 0.0:
            return  # the same point again (e.g. a glyph's repeated vertex): nothing to fly
        step = (p - a) * (min(s.corner_offset_m, dist / 3.0) / dist)
        if from_corner and np.any(step):
            self.leg(a + step, KIND_DENSE, stroke, KIND_DENSE, s.weight_dense, s.weight_dense)
        if to_corner and np.any(step):
            self.leg(p - step, KIND_DENSE, stroke, KIND_DENSE, s.weight_dense, s.weight_dense)
        self.leg(p, KIND_TURNING, stroke, KIND_DENSE, s.weight_dense)
        if to_corner and s.corner_dwell_s > 0.0:
            self._append(p, KIND_DENSE, stroke, s.weight_turning)
            self.durations.append(s.corner_dwell_s)


def _sharp_corners(xy: FloatArray, angle_deg: float) -> NDArray[np.bool_]:
    """Per turning point: does the path turn by more than ``angle_deg`` there? Ends: False."""
    sharp = np.zeros(xy.shape[0], dtype=bool)
    d = np.diff(xy, axis=0)
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-12)
    cos_turn = np.sum(d[:-1] * d[1:], axis=1)
    sharp[1:-1] = cos_turn < math.cos(math.radians(angle_deg))
    return sharp


def build_path(
    strokes_board_m: Sequence[FloatArray], board: BoardFrame, settings: PathSettings
) -> WritingPath:
    """The data path of a character (see module docstring)."""
    strokes = validate_strokes(strokes_board_m)
    write_z = board.surface_z_m + settings.write_height_m
    lift = np.array([0.0, 0.0, settings.clearance_m])
    b = _Builder(settings)
    ranges, windows, turning = [], [], []
    for k, stroke in enumerate(strokes):
        tp = stroke[split_and_merge(stroke, settings.split_threshold_m)]
        turning.append(tp)
        world = board.to_world(tp)
        world[:, 2] = write_z
        above = world[0] + lift
        if k == 0:
            b.start(above, KIND_PEN_UP, -1)
        else:
            b.leg(above, KIND_PEN_UP, -1, KIND_TRAVEL, settings.weight_travel)
        approach = len(b.points) - 1
        b.hop(world[0], KIND_TURNING, k)
        first = len(b.points) - 1
        sharp = _sharp_corners(world[:, :2], settings.corner_angle_deg)
        for i in range(1, world.shape[0]):
            b.stroke_leg(world[i], k, sharp[i - 1], sharp[i])
        ranges.append((first, len(b.points) - 1))
        b.hop(world[-1] + lift, KIND_PEN_UP, -1)
        windows.append((approach, len(b.points) - 1))
    return WritingPath(
        points_m_enu=np.array(b.points),
        weights=np.array(b.weights),
        kinds=np.array(b.kinds, dtype=np.int64),
        stroke_of_point=np.array(b.strokes, dtype=np.int64),
        segment_durations_s=np.array(b.durations),
        stroke_ranges=tuple(ranges),
        pen_windows=tuple(windows),
        turning_points_board_m=tuple(turning),
        write_z_m=write_z,
    )
