"""Per-vehicle paths of the current job: reference and flown positions with the pen state.

Pure. A track only grows while its job lasts; it restarts when the vehicle starts another job, so a
board keeps showing the last character written until the next one begins. Views draw a track
incrementally: :attr:`Track.generation` changes when the track restarts, :attr:`Track.count` says
how many points exist, so a view only draws the points it has not drawn yet.
"""

from __future__ import annotations

from dataclasses import dataclass

Vector3 = tuple[float, float, float]


@dataclass(frozen=True)
class TrackPoint:
    """One telemetry sample of a path."""

    position_m_enu: Vector3
    """Where the vehicle (its pen tip) was, world frame, in [m]."""
    reference_m_enu: Vector3 | None
    """Where it should have been, world frame, in [m]; None when the agent did not say."""
    pen_down: bool
    """Whether the pen touched the board at that instant."""
    force_n: float | None = None
    """Measured normal contact force in [N], for kinds that sense it."""
    force_reference_n: float | None = None
    """Wanted normal contact force in [N], for kinds that control it."""


class Track:
    """The path of one vehicle during one job, bounded in length."""

    def __init__(self, max_points: int = 20_000) -> None:
        if max_points < 2:
            raise ValueError("max_points must be >= 2")
        self.max_points = max_points
        """Points kept before the track starts over (20 000 points = 1000 s at 20 Hz)."""
        self.job_id: str | None = None
        """Job the path belongs to."""
        self.generation = 0
        """Incremented each time the track starts over."""
        self.points: list[TrackPoint] = []
        """Samples in arrival order."""

    @property
    def count(self) -> int:
        return len(self.points)

    def restart(self, job_id: str | None) -> None:
        """Forget the path and start one for ``job_id``."""
        self.job_id = job_id
        self.points = []
        self.generation += 1

    def add(self, job_id: str | None, point: TrackPoint) -> None:
        """Record a sample; a sample without a job leaves the track as it is (idle, landing)."""
        if job_id is None:
            return
        if job_id != self.job_id or len(self.points) >= self.max_points:
            self.restart(job_id)
        self.points.append(point)
