"""Pure safety checks of one vehicle: tracking deviation, geofence, writing bounds (no I/O)."""

from vehicle_agent.safety.geofence import Geofence, GeofenceError, vehicle_fence
from vehicle_agent.safety.limits import SafetyLimits, WritingBounds, writing_verdict
from vehicles.deviation import DeviationLimit, DeviationMonitor, DeviationTrip

__all__ = [
    "DeviationLimit",
    "DeviationMonitor",
    "DeviationTrip",
    "Geofence",
    "GeofenceError",
    "SafetyLimits",
    "WritingBounds",
    "vehicle_fence",
    "writing_verdict",
]
