"""The room's typed settings from the show file's ``omni_wheel`` section."""

from __future__ import annotations

from dataclasses import replace

from vehicles.omni_wheel.floor_plan import DEFAULT_SETTINGS, OmniSettings
from vehicles.omni_wheel.show_section import OmniWheelSettings
from vehicles.omni_wheel.terrain import Step, Terrain

_DYNAMIC_OVER_STATIC = (
    DEFAULT_SETTINGS.geometry.friction_dynamic / DEFAULT_SETTINGS.geometry.friction_static
)
"""The show file gives one roller friction: the dynamic one keeps the default rollers' ratio."""


def omni_settings(section: OmniWheelSettings) -> OmniSettings:
    """:class:`OmniSettings` of a show's ``omni_wheel`` section (defaults where it says nothing)."""
    geometry = replace(
        DEFAULT_SETTINGS.geometry,
        wheel_radius_m=section.wheel_radius_m,
        running_speed_mps=section.running_speed_mps,
        friction_static=section.roller_friction,
        friction_dynamic=section.roller_friction * _DYNAMIC_OVER_STATIC,
    )
    terrain = Terrain(
        steps=tuple(Step(s.x_m, s.height_m) for s in section.steps),
        half_width_m=section.terrain_half_width_m,
    )
    return replace(
        DEFAULT_SETTINGS,
        geometry=geometry,
        accel_max_mps2=section.accel_max_mps2,
        speed_max_mps=section.speed_max_mps,
        marker_width_m=section.marker_width_m,
        terrain=terrain,
    )
