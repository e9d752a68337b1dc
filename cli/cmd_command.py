"""``skyquill command SHOW.yaml ACTION [TARGET]``: operator commands from the shell.

Actions: ``pause [VEHICLE]``, ``resume [VEHICLE]``, ``cancel JOB``, ``approve JOB``,
``reject JOB``, ``prioritize JOB --priority N``, ``land VEHICLE``, ``land-all``,
``estop [VEHICLE]`` (no vehicle: every vehicle), ``clear_fault VEHICLE`` (the vehicle leaves
``fault`` if it is landed and disarmed), ``release VEHICLE`` (a held vehicle may take jobs
again), ``release-all`` (every held vehicle), ``fresh-sheet BOARD`` (a board waiting for a sheet
has a fresh one), ``battery-swapped VEHICLE`` (the crew put a fresh battery in a vehicle waiting
for one). A vehicle may also be named with ``--vehicle ID``.
``land-all`` is the bus command ``land_all``; either spelling is accepted (also ``clear-fault``,
``release-all``, ``battery-swapped``).

``reject`` and ``cancel`` also take many waiting jobs at once, in one command: ``--client ID``
(every waiting job that client handed in) or ``--job ID`` repeated (a selection). Jobs a vehicle
has are left alone; the one-line answer says how many were taken and which were skipped, and why.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

NAME = "command"
HELP = "Operator command: pause/resume/cancel/approve/reject/prioritize/land/land-all/estop/..."

JOB_ACTIONS = ("cancel", "approve", "reject", "prioritize")
SWAP_ACTIONS = ("battery_swapped", "battery-swapped")
VEHICLE_ACTIONS = (
    *("pause", "resume", "land", "estop", "clear_fault", "clear-fault", "release"),
    *SWAP_ACTIONS,
)
NEEDS_VEHICLE = ("land", "clear_fault", "clear-fault", "release", *SWAP_ACTIONS)
BOARD_ACTIONS = ("fresh_sheet", "fresh-sheet")
FLEET_ACTIONS = ("land-all", "land_all", "release-all", "release_all")
BULK_ACTIONS = ("reject", "cancel")
ACTIONS = (*JOB_ACTIONS, *VEHICLE_ACTIONS, *BOARD_ACTIONS, *FLEET_ACTIONS)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument("action", choices=ACTIONS, help="what to do")
    parser.add_argument("target", nargs="?", help="job id, vehicle id or board id (fresh-sheet)")
    parser.add_argument("--vehicle", metavar="ID", help="the vehicle (vehicle actions)")
    parser.add_argument("--priority", type=int, help="new priority (prioritize)")
    parser.add_argument(
        "--job",
        dest="jobs",
        action="append",
        metavar="ID",
        help="reject/cancel: a job of a selection (repeat it for more)",
    )
    parser.add_argument(
        "--client", metavar="ID", help="reject/cancel: every waiting job of this client"
    )
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


def _bulk_fields(args: argparse.Namespace) -> dict[str, object] | str:
    """``job_ids`` or ``client_id`` of a bulk reject/cancel, or what is wrong with them."""
    if args.action not in BULK_ACTIONS:
        return f"--job and --client go with {' or '.join(BULK_ACTIONS)}, not {args.action}"
    if sum(1 for given in (args.target, args.jobs, args.client) if given) > 1:
        return f"{args.action} takes one of a job id, --job or --client"
    return {"job_ids": args.jobs} if args.jobs else {"client_id": args.client}


def run(args: argparse.Namespace) -> int:
    action = args.action.replace("-", "_")
    fields: dict[str, object] = {"reason": args.reason, "operator": args.operator}
    if args.jobs or args.client is not None:
        bulk = _bulk_fields(args)
        if isinstance(bulk, str):
            print(f"skyquill command: {bulk}", file=sys.stderr)
            return 2
        return send(args.show, action, **fields, **bulk)
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
        vehicle = args.vehicle or args.target
        if args.action in NEEDS_VEHICLE and not vehicle:
            print(f"skyquill command: {args.action} needs a vehicle id", file=sys.stderr)
            return 2
        if vehicle:
            fields["vehicle_id"] = vehicle
    elif args.action in BOARD_ACTIONS:
        if not args.target:
            print(f"skyquill command: {args.action} needs a board id", file=sys.stderr)
            return 2
        fields["board_id"] = args.target
    return send(args.show, action, **fields)
