"""The hexarotor sponge writer's default figures, in one light module (plain constants, no imports):
the kind's own settings (:class:`~vehicles.hexarotor_sponge.params.HexarotorParams`,
:class:`~vehicles.hexarotor_sponge.pen.PenCurve`, :class:`~vehicles.hexarotor_sponge.limits.Limits`,
:class:`~vehicles.hexarotor_sponge.plan.PlanSettings`) and a show file's ``hexarotor`` section
(``vehicles.hexarotor_sponge.show_section``, which the show file loads: it cannot import the
CasADi/MuJoCo modules) both default to these, so a show left at its defaults and ``skyquill fly
--kind hexarotor-sponge`` plan and fly the same vehicle
(held by tests/test_wall_kind.py::test_one_set_of_defaults_for_shows_and_fly)."""

from __future__ import annotations

ROTOR_TILT_RAD = 0.52
"""Tilt of each rotor about its arm, alternating sign, [rad] (29.79 deg; the paper's vehicle
tilts its rotors about 30 deg). The value the wall benchmarks were measured with; a show file
states it in degrees."""
THRUST_MAX_N = 14.0
"""Largest thrust of one rotor, [N]."""
ARM_LENGTH_M = 0.40
"""From the F/T sensor to the pen tip (spring at its stop), [m]."""
WALL_FRICTION = 0.4
"""Coulomb friction coefficient of pen on wall (measured in the paper)."""

V_MAX_MPS = 0.20
"""Largest speed of the writing point, [m/s] (paper: 20 cm/s)."""
A_MAX_MPS2 = 0.20
"""Largest acceleration of the writing point, [m/s^2] (paper: 20 cm/s^2)."""
FORCE_RATE_MAX_NPS = 2.0
"""Largest change of the normal force, [N/s] (paper: 2 N/s)."""
REACH_M = 1.5
"""Farthest a stroke point may lie from the centre of the writing area, [m]."""
REACH_SLACK_M = 1e-3
"""Distance a stroke point or a writing area's corner may lie beyond the reach, [m]: a layout's
rounding (a 2.4 m x 1.8 m area's corner is 1.5 m away to within a float's last bits). What is
refused is then at least 1 mm beyond, and the refusal, in millimetres, says so."""

PEN_WIDTH_COEFFICIENTS_M = (2.0e-3, 3.2e-3, -0.2e-3)
"""Line width [m] as a polynomial of normal force [N], lowest order first (the shape of the
paper's Fig. 4c: about 5 mm at 1 N to 14 mm at 6 N)."""
PEN_FORCE_MIN_N = 1.0
"""Lowest calibrated normal force, [N]."""
PEN_FORCE_MAX_N = 6.0
"""Highest calibrated normal force, [N]."""
PEN_STIFFNESS_NPM = 400.0
"""Pen spring stiffness, [N/m]."""
PEN_PRELOAD_N = 0.5
"""Pen spring preload, [N]: below it the pen does not slide back."""
DEFAULT_WIDTH_M = 9e-3
"""Line width of strokes that carry none, [m]."""
CLAMP_WIDTHS = False
"""Clamp wanted widths outside the pen's range instead of refusing the job."""
