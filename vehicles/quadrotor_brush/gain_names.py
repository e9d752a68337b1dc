"""The names a show file's ``controller.overrides`` may give (plain data: the show file reads
them without importing the controller).

Each is ``<axis>.<parameter>``: an RPT design parameter (eq. 9 of Phang et al. 2015;
``control/rpt.py: RptAxisGains``) of one world axis, replacing the preset's. A test holds them
equal to the gains' fields.
"""

from __future__ import annotations

AXES = ("x", "y", "z")
"""World axes (ENU) with gains of their own."""
PARAMETERS = ("eps", "wn_radps", "zeta", "ki_radps")
"""The design parameters of an axis: time scale, natural frequency in [rad/s], damping ratio,
integral pole in [rad/s] (each positive)."""
GAIN_NAMES = tuple(f"{axis}.{parameter}" for axis in AXES for parameter in PARAMETERS)
"""Every name ``controller.overrides`` may give, e.g. ``x.eps``."""
