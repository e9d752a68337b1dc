"""A running show followed as a Foxglove scene: each bus message in, the scene's messages out.

:class:`ShowScene` is the ``derive`` of the show's recorder (``bus.recorder``) and the heart of
the live view (``scene.live``): telemetry moves the vehicles' frames and feeds the plot series
(``/plot``, one topic: a layout picks a vehicle with ``/plot{vehicle_id=="uav1"}``) and the
paths, events become log lines, and the fixed venue is sent again every
:data:`VENUE_PERIOD_S`, so a recording opened or a viewer joining at any time has it.
"""

from __future__ import annotations

from collections.abc import Iterator

import foxglove.messages as fg
import msgspec

from bus.mcap_channels import DerivedMessage
from bus.messages import Event, Telemetry
from scene.encode import declared, encoded, json_declared, json_encoded, timestamp
from scene.models import vehicle_models
from scene.vehicles import JobPaths, transforms
from scene.venue import venue_update
from showfile import Show

TF_TOPIC, VENUE_TOPIC, VEHICLES_TOPIC = "/tf", "/scene/venue", "/scene/vehicles"
PATHS_TOPIC, LOG_TOPIC, PLOT_TOPIC = "/scene/paths", "/log", "/plot"
VENUE_PERIOD_S = 10.0
"""The venue and the vehicle models are sent again this often, in [s] of log time."""
PATHS_PERIOD_S = 0.5
"""A vehicle's paths are sent at most this often, in [s] (they grow by 10 points)."""
PLOT_SCHEMA_NAME = "skyquill.WritingPlot"
LOG_LEVELS = {"info": fg.LogLevel.Info, "warning": fg.LogLevel.Warning, "alert": fg.LogLevel.Error}
PLOT_SCHEMA = {
    "title": PLOT_SCHEMA_NAME,
    "type": "object",
    "properties": {
        "vehicle_id": {"type": "string"},
        "tracking_error_m": {"type": "number", "description": "distance to the reference [m]"},
        "force_n": {"type": ["number", "null"], "description": "measured contact force [N]"},
        "force_reference_n": {"type": ["number", "null"], "description": "wanted force [N]"},
        "pen_down": {"type": "boolean"},
        "progress": {"type": "number", "description": "share of the job written, 0..1"},
    },
    "required": ["vehicle_id", "tracking_error_m", "pen_down", "progress"],
}


def scene_channels() -> list[DerivedMessage]:
    """Every topic :class:`ShowScene` sends on, each with the schema its messages carry and no
    message (an empty payload): the live view opens all its channels from these before a viewer
    can connect (``scene.live``)."""
    protobuf = {
        TF_TOPIC: fg.FrameTransforms,
        VENUE_TOPIC: fg.SceneUpdate,
        VEHICLES_TOPIC: fg.SceneUpdate,
        PATHS_TOPIC: fg.SceneUpdate,
        LOG_TOPIC: fg.Log,
    }
    channels = [declared(topic, message_type) for topic, message_type in protobuf.items()]
    return [*channels, json_declared(PLOT_TOPIC, PLOT_SCHEMA_NAME, PLOT_SCHEMA)]


class ShowScene:
    """The scene of one show, kept up to date message by message (one thread at a time)."""

    def __init__(self, show: Show, *, venue_period_s: float = VENUE_PERIOD_S) -> None:
        self.show = show
        self.venue_period_s = venue_period_s
        """The venue and the vehicle models are sent again this often, in [s] of log time."""
        self._paths: dict[str, JobPaths] = {}
        self._paths_sent_ns: dict[str, int] = {}
        self._venue_sent_ns: int | None = None

    def derive(
        self, topic: str, message: msgspec.Struct | None, stamp_ns: int
    ) -> list[DerivedMessage]:
        """The scene's messages caused by one bus message, decoded as its topic's type (a
        recorder's ``derive``: ``bus.recorder.Derive``)."""
        out = list(self.fixed(stamp_ns))
        if isinstance(message, Telemetry):
            out += self.telemetry(message, stamp_ns)
        elif isinstance(message, Event):
            out.append(self.event(message, stamp_ns))
        return out

    def fixed(self, stamp_ns: int, *, force: bool = False) -> Iterator[DerivedMessage]:
        """The venue and the vehicle models, when they are due (or ``force``)."""
        last = self._venue_sent_ns
        if force or last is None or stamp_ns - last >= self.venue_period_s * 1e9:
            self._venue_sent_ns = stamp_ns
            yield encoded(VENUE_TOPIC, venue_update(self.show, stamp_ns))
            yield encoded(VEHICLES_TOPIC, vehicle_models(self.show, stamp_ns))

    def telemetry(self, t: Telemetry, stamp_ns: int) -> list[DerivedMessage]:
        """A vehicle's frames and plot sample; its paths at most every :data:`PATHS_PERIOD_S`."""
        out = [
            encoded(TF_TOPIC, transforms(t, stamp_ns)),
            json_encoded(
                PLOT_TOPIC,
                PLOT_SCHEMA_NAME,
                PLOT_SCHEMA,
                {
                    "vehicle_id": t.vehicle_id,
                    "tracking_error_m": t.tracking_error_m,
                    "force_n": t.force_n,
                    "force_reference_n": t.force_reference_n,
                    "pen_down": t.pen_down,
                    "progress": t.progress,
                },
            ),
        ]
        paths = self._paths.setdefault(t.vehicle_id, JobPaths())
        job_before = paths.job_id
        paths.add(t)
        last = self._paths_sent_ns.get(t.vehicle_id)
        due = last is None or stamp_ns - last >= PATHS_PERIOD_S * 1e9
        if due or paths.job_id != job_before:
            self._paths_sent_ns[t.vehicle_id] = stamp_ns
            update = fg.SceneUpdate(entities=[paths.entity(t.vehicle_id, stamp_ns)])
            out.append(encoded(PATHS_TOPIC, update))
        return out

    def event(self, event: Event, stamp_ns: int) -> DerivedMessage:
        """An event of the show's log as a Foxglove log line."""
        name = event.kind if event.vehicle_id is None else f"{event.kind} {event.vehicle_id}"
        line = fg.Log(
            timestamp=timestamp(stamp_ns),
            level=LOG_LEVELS.get(event.level, fg.LogLevel.Unknown),
            message=event.message,
            name=name,
        )
        return encoded(LOG_TOPIC, line)
