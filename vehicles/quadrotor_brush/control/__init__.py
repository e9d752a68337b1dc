"""Pure controllers of the vehicle agent, vectorised over N vehicles and tested alone.

- :mod:`rpt`: RPT outer loop per axis (Phang 2015 eq. 6-9), published and shipped gains;
- :mod:`estimator`: position/velocity/disturbance filter from delayed noisy motion capture;
- :mod:`inner`: acceleration command -> (throttle, roll, pitch) through G_c (eq. 1-2);
- :mod:`tip`: reference preparation that aims the tilting brush tip and leads the inner loop;
- :mod:`controller`: all of it, one call per control tick (``body_reference`` once per job);
- :mod:`config`: the controller's settings and presets (what a plan's settings hold of it).
"""
