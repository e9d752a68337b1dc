"""A brush on a linear bearing: free travel along the body z axis, width grows with press.

The shaft hangs along ``-n`` (``n`` the body z axis) from the vehicle reference point; fully
extended its tip is ``length_m`` away. Touching the horizontal board it slides up the bearing
without pushing the vehicle (ideal bearing: no force reaches the body), so the board never changes
the flight. The press is how far the shaft slid up; it sets the footprint width.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from vehicles.quadrotor_brush.params import BrushParams

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

_UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class BrushState:
    """Brush of N vehicles at one instant."""

    tip_m_enu: FloatArray
    """Brush tip in [m], shape (N, 3); on the board surface while in contact."""
    press_m: FloatArray
    """Slide of the shaft up the bearing in [m], shape (N,); 0 without contact."""
    width_m: FloatArray
    """Footprint diameter in [m], shape (N,); 0 without contact."""
    contact: BoolArray
    """Whether the tip touches the board, shape (N,)."""
    bottomed: BoolArray
    """Whether the press exceeds the bearing travel (the stop would hit), shape (N,)."""


def writing_point(position_m_enu: FloatArray, body_z_enu: FloatArray, lever_m: float) -> FloatArray:
    """The writing point in [m] of vehicles at ``position_m_enu`` with axis ``body_z_enu`` (any
    shape (..., 3)): one ``lever_m`` (reference point to tip at nominal press) down the brush
    axis, ``p - lever * (n - e_z)``; level, the vehicle reference point itself."""
    point: FloatArray = position_m_enu - lever_m * (body_z_enu - _UP)
    return point


def brush_state(
    params: BrushParams,
    position_m_enu: FloatArray,
    body_z_enu: FloatArray,
    board_height_m: float,
) -> BrushState:
    """Tip position, press and width for vehicles at ``position_m_enu`` with axis ``body_z_enu``."""
    free_tip_z = position_m_enu[:, 2] - params.length_m * body_z_enu[:, 2]
    depth = board_height_m - free_tip_z
    contact = depth > 0.0
    press = np.where(contact, depth / body_z_enu[:, 2], 0.0)
    bottomed = press > params.travel_m
    press = np.minimum(press, params.travel_m)
    lever = params.length_m - press
    tip = position_m_enu - lever[:, None] * body_z_enu
    width = np.where(contact, params.tip_width_m + params.width_per_press * press, 0.0)
    return BrushState(tip, press, width, contact, bottomed)
