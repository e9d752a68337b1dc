"""The Zenoh ``access_control`` section of a show, generated from its fleet (pure, default deny).

The router enforces it on every message that enters it from a client (``ingress``). What each
identity may *send* is listed; what it may *receive* follows from what it may subscribe to and
query, so egress is open inside the show's namespace. The rules Zenoh cannot express (a report
only for a job assigned to its vehicle; a vehicle's messages naming that vehicle) are checked by
the orchestrator and the agents on top: each agent reports on its own key, so the key says who.

What each identity may send:

- ``orchestrator``: anything under ``skyquill/<show>/**``;
- each vehicle: telemetry, status, events and its liveliness token under its own keys; replies
  of its own ``command`` and ``assign`` queryables; reports on its own report key; queries of
  the orchestrator's ``clock`` (its clock against the orchestrator's, for its preflight);
- ``kiosk`` and each outside ``submitter``: submissions on their own submit key
  (``orchestrator/submit/<identity>``, so the orchestrator's quotas count by certificate), and
  snapshot queries; they follow jobs and the fleet;
- ``operator`` (the console, the CLI) and each outside ``operator``: operator commands and
  submissions (the console's on ``orchestrator/command`` and ``orchestrator/submit``, an outside
  one's on its own keys, ``command/<identity>`` and ``submit/<identity>``, so the event log names
  who sent each command), snapshots and vehicle commands (never an assignment); they watch
  everything;
- ``crew`` (the kiosk's second session, behind its crew page): commands on its own key
  (``orchestrator/command/crew``, where the orchestrator takes ``fresh_sheet`` and
  ``battery_swapped`` from it and refuses anything else); it follows the
  fleet; never a vehicle's key, a submission or the operators' ``command``;
- each outside ``watcher``: snapshot queries; it watches everything;
- ``router``: anything (the ground station's router, as a companion host's router sees it);
- ``router@<host>``, a companion host's router: what the vehicles on that host may send, and
  nothing else (``trust/hosts.py``).

Outside clients are subjects one by one (``<role>@<name>``, ``trust/clients.py``): a client not
listed, or revoked, matches no subject, and default deny leaves it nothing to send or receive.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from bus.keys import ShowKeys

PUBLISH = ("put",)
SUBSCRIBE = ("declare_subscriber",)
QUERY = ("query",)
SERVE = ("declare_queryable", "reply")
TOKEN = ("liveliness_token",)
WATCH_PRESENCE = ("declare_liveliness_subscriber", "liveliness_query")
ALL_MESSAGES = ("delete", *PUBLISH, *SUBSCRIBE, *QUERY, *SERVE, *TOKEN, *WATCH_PRESENCE)


def _rule(rule_id: str, messages: Sequence[str], key_exprs: Iterable[str]) -> dict[str, Any]:
    return {
        "id": rule_id,
        "permission": "allow",
        "flows": ["ingress"],
        "messages": list(messages),
        "key_exprs": list(key_exprs),
    }


def _watch_all(keys: ShowKeys, name: str) -> list[dict[str, Any]]:
    everything = [f"{keys.prefix}/**"]
    return [
        _rule(f"{name}: watch", (*SUBSCRIBE, *WATCH_PRESENCE), everything),
        _rule(f"{name}: snapshot", QUERY, [keys.snapshot]),
    ]


def _follow_jobs(keys: ShowKeys, name: str) -> list[dict[str, Any]]:
    return [
        _rule(f"{name}: submit", QUERY, [keys.submit_as(name), keys.snapshot]),
        _rule(f"{name}: follow", SUBSCRIBE, [keys.jobs_all, keys.fleet]),
        _rule(f"{name}: presence", WATCH_PRESENCE, [keys.orchestrator_alive]),
    ]


def _operator(keys: ShowKeys, name: str, command_key: str, submit_key: str) -> list[dict[str, Any]]:
    return [
        *_watch_all(keys, name),
        _rule(f"{name}: command", QUERY, [command_key, submit_key]),
        _rule(f"{name}: vehicles", QUERY, [f"{keys.prefix}/vehicles/*/command"]),
    ]


def _crew(keys: ShowKeys) -> list[dict[str, Any]]:
    return [
        _rule("crew: confirm", QUERY, [keys.command_as("crew")]),
        _rule("crew: follow", SUBSCRIBE, [keys.fleet]),
        _rule("crew: presence", WATCH_PRESENCE, [keys.orchestrator_alive]),
    ]


def _client(keys: ShowKeys, common_name: str, role: str) -> list[dict[str, Any]]:
    """An outside client's rules: its role's, submitting on its own key."""
    if role == "operator":
        return _operator(
            keys, common_name, keys.command_as(common_name), keys.submit_as(common_name)
        )
    if role == "submitter":
        return _follow_jobs(keys, common_name)
    return _watch_all(keys, common_name)


def _vehicle(keys: ShowKeys, vehicle_id: str) -> list[dict[str, Any]]:
    name = f"vehicle {vehicle_id}"
    own = [keys.telemetry(vehicle_id), keys.vehicle_status(vehicle_id)]
    return [
        _rule(f"{name}: publish", PUBLISH, [*own, keys.vehicle_events(vehicle_id)]),
        _rule(f"{name}: serve", SERVE, [keys.vehicle_command(vehicle_id)]),
        _rule(f"{name}: take jobs", SERVE, [keys.vehicle_assign(vehicle_id)]),
        _rule(f"{name}: alive", TOKEN, [keys.vehicle_alive(vehicle_id)]),
        _rule(f"{name}: report", QUERY, [keys.report(vehicle_id)]),
        _rule(f"{name}: clock", QUERY, [keys.clock]),
        _rule(f"{name}: orchestrator", WATCH_PRESENCE, [keys.orchestrator_alive]),
    ]


def _egress(keys: ShowKeys) -> dict[str, Any]:
    rule = _rule("receive inside the show", ALL_MESSAGES, [f"{keys.prefix}/**"])
    rule["flows"] = ["egress"]
    return rule


def _companion(keys: ShowKeys, router: str, vehicle_ids: Sequence[str]) -> list[dict[str, Any]]:
    """A companion router forwards its vehicles' messages: their rules, under its own name."""
    rules = []
    for vehicle_id in vehicle_ids:
        for rule in _vehicle(keys, vehicle_id):
            rules.append({**rule, "id": f"{router}: {rule['id']}"})
    return rules


def access_control(
    show_id: str,
    vehicle_ids: Sequence[str],
    companion_routers: Mapping[str, Sequence[str]] | None = None,
    clients: Mapping[str, str] | None = None,
) -> dict[str, Any]:
    """The ``access_control`` section for the show's routers (default deny);
    ``companion_routers``: each companion host's router identity and its vehicles;
    ``clients``: each admitted outside client's common name and role."""
    keys = ShowKeys(show_id)
    everything = [f"{keys.prefix}/**"]
    egress = _egress(keys)
    per_subject: dict[str, list[dict[str, Any]]] = {
        "router": [_rule("router: anything", ALL_MESSAGES, ["**"])],
        "orchestrator": [_rule("orchestrator: anything in the show", ALL_MESSAGES, everything)],
        "kiosk": _follow_jobs(keys, "kiosk"),
        "operator": _operator(keys, "operator", keys.command, keys.submit),
        "crew": _crew(keys),
    }
    for common_name, role in (clients or {}).items():
        per_subject[common_name] = _client(keys, common_name, role)
    for vehicle_id in vehicle_ids:
        per_subject[vehicle_id] = _vehicle(keys, vehicle_id)
    for router, carried in (companion_routers or {}).items():
        per_subject[router] = _companion(keys, router, carried)
    rules = [egress]
    subjects = []
    policies = []
    for common_name, own_rules in per_subject.items():
        rules += own_rules
        subjects.append({"id": f"cn {common_name}", "cert_common_names": [common_name]})
        policies.append(
            {
                "id": f"policy {common_name}",
                "rules": [egress["id"], *(r["id"] for r in own_rules)],
                "subjects": [f"cn {common_name}"],
            }
        )
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }
