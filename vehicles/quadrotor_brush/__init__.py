"""The brush quadrotor over a horizontal board (Airshow, Phang et al. 2015): everything that is
its own, behind ``vehicles.quadrotor_brush.kind.KIND``. Importing this package imports nothing
else (``mavsim`` reads only its dynamics)."""
