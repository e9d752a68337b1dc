"""A MAVLink vehicle for tests and rehearsal: simulated vehicles that answer like an autopilot."""
