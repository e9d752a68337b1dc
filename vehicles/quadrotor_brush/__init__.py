"""The brush quadrotor over a horizontal board (Airshow, Phang et al. 2015): everything that is
its own, behind ``vehicles.quadrotor_brush.kind.KIND``. Importing this package imports nothing
else (``mavsim`` reads only its dynamics)."""

KIND_NAME = "quadrotor-brush"
"""The kind's name in show files (``vehicles.ROOMS``), for what is the brush quadrotor's own
(the CLI's brush options) without importing the kind."""
