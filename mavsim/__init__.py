"""A MAVLink vehicle for tests and rehearsal: simulated vehicles that answer like an autopilot.

- :mod:`mavsim.autopilot` (pure): an ArduCopter-like mode logic, arming checks, take-off, GUIDED
  setpoint following with GUID_TIMEOUT, LAND (its state and commands in
  :mod:`mavsim.autopilot_core`); :mod:`mavsim.px4` the PX4 OFFBOARD differences;
- :mod:`mavsim.control` (pure): the autopilot's own position controller (PID + feed-forward);
  :mod:`mavsim.shaping` (pure): ArduCopter's jerk-limited path towards a guided target;
- :mod:`mavsim.airframe`: the simulator's quadrotor physics
  (``vehicles.quadrotor_brush.dynamics``) on the ground;
- :mod:`mavsim.endpoint`: one vehicle on a UDP port, MAVLink 2 bytes in and out (pymavlink);
- :mod:`mavsim.server`: several vehicles in real time (or faster) on one thread;
- :mod:`mavsim.show`: a show file's ``backend: mavlink`` vehicles as vehicle configurations.

``skyquill sim-mavlink SHOW.yaml`` runs them. It knows no service (import-linter).
"""
