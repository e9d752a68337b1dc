"""``skyquill approve SHOW.yaml JOB_ID``: approve a submission of a moderated show."""

from __future__ import annotations

import argparse
from pathlib import Path

NAME = "approve"
HELP = "Approve a submission waiting for moderation."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument("job_id", help="the job to approve")
    parser.add_argument("--operator", default="operator", help="name recorded in the event log")


def run(args: argparse.Namespace) -> int:
    from cli.cmd_command import send

    return send(args.show, "approve", job_id=args.job_id, operator=args.operator)
