"""What an agent flies: ``base`` (the protocol), ``sim`` (in-process simulator), ``kinematic``
(an ideal point vehicle for tests and benchmarks) and the ``mavlink`` package (PX4 / ArduPilot)."""
