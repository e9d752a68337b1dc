"""The omnidirectional step-climbing ground writer (Chugo et al.): seven actuated wheels with free
rollers, a passive suspension with free joint 1 at axle height, wheel references from the body
configuration; it writes with a marker on the floor. The kind object is
``vehicles.omni_wheel.kind.KIND`` (imported lazily: it pulls in the planner; MuJoCo only when it
drives). The show file reads only the light ``show_section`` (the ``omni_wheel`` section and the
floor-area check), ``check_route`` and ``terrain``."""
