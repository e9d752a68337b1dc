"""The MAVLink backend: an agent flies a PX4 or ArduPilot vehicle (or ``skyquill sim-mavlink``).

``create.create_backend`` builds a :class:`~vehicle_agent.backends.mavlink.backend.MavlinkBackend`
(``backend.py``) from a show's vehicle (``settings.py``, ``url.py``). Around it, from the wire up:
``link.py`` (bytes <-> messages), ``state.py`` (what the autopilot said), ``commands.py`` and
``params.py`` (commands and parameters, acknowledged), ``connect.py`` (the handshake),
``stream.py`` and ``setpoints.py`` (setpoints at their rate), ``frames.py`` (ENU <-> NED here
only), ``mocap.py`` and ``odometry.py`` (the position source), ``watchdog.py`` (is it still ours
to fly), ``health.py`` (preflight), ``snapshot.py`` (what the agent sees each tick), ``truth.py``,
``truth_filter.py``, ``lag.py`` and ``response.py`` (the vehicle's true state and lag, SITL),
``pen.py``, ``battery.py``, ``errors.py``. Each module's docstring says whether it is pure.
"""
