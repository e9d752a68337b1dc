"""``skyquill command SHOW.yaml ACTION [TARGET]``: operator commands from the shell.

Actions: ``pause [VEHICLE]``, ``resume [VEHICLE]``, ``cancel JOB``, ``approve JOB``,
``reject JOB``, ``prioritize JOB --priority N``, ``land VEHICLE``, ``land-all``,
``estop [VEHICLE]`` (no vehicle: every vehicle).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

NAME = "command"
HELP = "Operator command: pause/resume/cancel/approve/reject/prioritize/land/land-all/estop."

JOB_ACTIONS = ("cancel", "approve", "reject", "prioritize")
VEHICLE_ACTIONS = ("pause", "resume", "land", "estop")
ACTIONS = (*JOB_ACTIONS, *VEHICLE_ACTIONS, "land-all")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument("action", choices=ACTIONS, help="what to do")
    parser.add_argument("target", nargs="?", help="job id (job actions) or vehicle id")
    parser.add_argument("--priority", type=int, help="new priority (prioritize)")
    parser.add_argument("--reason", default="", help="why (kept in the event log)")
    parser.add_argument("--operator", default="operator", help="name recorded in the event log")


def send(show_path: Path, command: str, **fields: object) -> int:
    """Send one operator command; print the reply; 0 if accepted, 1 if refused, 2 if unreachable."""
    from bus.messages import OperatorCommand
    from bus.rpc import NoReplyError, RemoteError
    from bus.session import SessionOpenError
    from orchestrator.client import command as send_command
    from showfile import ShowError, load_show

    try:
        show = load_show(show_path)
        reply = send_command(show, OperatorCommand(command=command, **fields))  # type: ignore[arg-type]
    except (ShowError, SessionOpenError, NoReplyError) as exc:
        print(f"skyquill {command}: {exc}", file=sys.stderr)
        return 2
    except RemoteError as exc:
        print(f"skyquill {command}: refused: {exc}", file=sys.stderr)
        return 1
    if not reply.ok:
        print(f"skyquill {command}: refused: {reply.message}", file=sys.stderr)
        return 1
    print(reply.message)
    return 0


def run(args: argparse.Namespace) -> int:
    action = args.action.replace("-", "_")
    fields: dict[str, object] = {"reason": args.reason, "operator": args.operator}
    if args.action in JOB_ACTIONS:
        if not args.target:
            print(f"skyquill command: {args.action} needs a job id", file=sys.stderr)
            return 2
        fields["job_id"] = args.target
        if args.action == "prioritize":
            if args.priority is None:
                print("skyquill command: prioritize needs --priority", file=sys.stderr)
                return 2
            fields["priority"] = args.priority
    elif args.action in VEHICLE_ACTIONS:
        if args.action == "land" and not args.target:
            print("skyquill command: land needs a vehicle id (or use land-all)", file=sys.stderr)
            return 2
        if args.target:
            fields["vehicle_id"] = args.target
    return send(args.show, action, **fields)
