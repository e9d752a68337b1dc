"""Write ``docs/foxglove-layout.json``: the Foxglove layout for skyquill's recordings, replays
and live view (a 3D panel on the scene, a plot of one vehicle's tracking error and force, the
show's log), built with ``foxglove.layouts`` so that it is a layout Foxglove reads.

    .venv/bin/python scripts/docs/foxglove_layout.py [--check]

The plotted vehicle is the layout's variable ``vehicle`` (``uav1``; change it in Foxglove's
Variables panel). ``--check`` exits 1 when the committed file differs from a fresh one.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import foxglove.layouts as fl

from scene.show_scene import LOG_TOPIC, PATHS_TOPIC, PLOT_TOPIC, VEHICLES_TOPIC, VENUE_TOPIC

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "foxglove-layout.json"
PLOTTED = (
    ("tracking_error_m", "tracking error [m]", "#0087ff"),
    ("force_n", "force [N]", "#ff5f00"),
    ("force_reference_n", "force wanted [N]", "#8a8a8a"),
)


def layout() -> fl.Layout:
    scene = {
        topic: fl.BaseRendererSceneUpdateTopicSettings(visible=True)
        for topic in (VENUE_TOPIC, VEHICLES_TOPIC, PATHS_TOPIC)
    }
    three_d = fl.ThreeDeePanel(
        title="show (world: x east, y north, z up)",
        config=fl.ThreeDeeConfig(topics=scene, follow_tf="world"),  # type: ignore[arg-type]
    )
    plot = fl.PlotPanel(
        title="writing of $vehicle",
        config=fl.PlotConfig(
            paths=[
                fl.PlotSeries(
                    value=f"{PLOT_TOPIC}{{vehicle_id==$vehicle}}.{field}",
                    label=label,
                    color=colour,
                    enabled=True,
                    timestamp_method="receiveTime",
                )
                for field, label, colour in PLOTTED
            ],
            show_legend=True,
        ),
    )
    log = fl.LogPanel(title="events", config=fl.LogConfig(topic_to_render=LOG_TOPIC))
    right = fl.SplitContainer(
        direction="column",
        items=[
            fl.SplitItem(content=plot, proportion=1.0),
            fl.SplitItem(content=log, proportion=1.0),
        ],
    )
    content = fl.SplitContainer(
        direction="row",
        items=[
            fl.SplitItem(content=three_d, proportion=2.0),
            fl.SplitItem(content=right, proportion=1.0),
        ],
    )
    return fl.Layout(variables={"vehicle": "uav1"}, content=content)


def rendered() -> str:
    return json.dumps(json.loads(layout().to_json()), indent=2, sort_keys=True) + "\n"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if the file is stale")
    args = parser.parse_args()
    text = rendered()
    if args.check:
        if OUT.read_text(encoding="utf-8") != text:
            print(f"{OUT.relative_to(ROOT)} is stale: run {Path(__file__).relative_to(ROOT)}")
            return 1
        return 0
    OUT.write_text(text, encoding="utf-8")
    print(f"wrote {OUT.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
