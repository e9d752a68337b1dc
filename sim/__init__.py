"""What the vehicle kinds' simulated worlds share: wind and motion-capture parameters
(``params``), seeded per-vehicle noise streams (``noise``), the ink raster and its IoU (``ink``),
synthetic writing references for tests and benchmarks (``reference``) and the simulator's one
exception (``errors``).

The vehicles themselves, their inner loops and worlds live in their rooms, ``vehicles/<kind>/``
(the brush quadrotor's dynamics and world in ``vehicles/quadrotor_brush/``); the writing surfaces
are ``vehicles.surface`` and ``planner.board``. Pure numerics: no transport, no services, no other
skyquill package (enforced by import-linter).
"""
