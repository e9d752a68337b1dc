"""Pure safety checks of one vehicle: tracking deviation, geofence, writing bounds (no I/O)."""

from showfile.geofence import Geofence, GeofenceError, vehicle_fence
from vehicle_agent.safety.limits import SafetyLimits
from vehicles.deviation import DeviationLimit, DeviationMonitor, DeviationTrip
from vehicles.verdict import WritingBounds, writing_verdict

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
