"""Submission quotas per identity on the bus (pure: the caller passes the time).

Who submits is the identity of the key the submission came on (``orchestrator/submit/<identity>``,
``bus/keys.py``): on a secured show the router's access control lets each certificate query
only its own key, so a client cannot spend another's quota nor escape its own by changing its
self-declared ``client_id``. With ``security: none`` there is no access control and the identity
is only a claim: anyone may submit under any name.

- the show's operators (``operator``, the console and the CLI, and each outside ``operator@<name>``)
  have no quota: the operator's own submissions are never starved by others (they may cancel any
  job anyway);
- the kiosk (``kiosk``) submits for all its visitors, each limited per address by the kiosk
  itself; as a whole it may submit ``policy.kiosk_submits_per_minute``;
- any other identity (an outside ``submitter@<name>``) may submit
  ``policy.client_submits_per_minute``, and have ``policy.client_max_waiting`` jobs waiting
  (awaiting approval or queued) at once.

Every attempt counts, as at the kiosk: a refused or invalid submission spends quota too, so a
flood costs the orchestrator one refusal each, before any parsing. Refusals are ``rate_limited``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from bus.messages import ErrorInfo
from bus.ratelimit import SlidingWindowLimiter
from showfile import Show

OPERATOR = "operator"
"""The identity of the show's own operator (the console, the CLI): ``orchestrator/submit``."""
KIOSK = "kiosk"
WINDOW_S = 60.0
"""Length of the sliding window of the per-minute quotas, [s]."""


def is_operator(identity: str) -> bool:
    """Whether ``identity`` is one of the show's operators (never refused for quota)."""
    return identity == OPERATOR or identity.startswith(f"{OPERATOR}@")


@dataclass(frozen=True)
class QuotaPolicy:
    """The show's quotas (``policy`` section)."""

    client_per_minute: int = 6
    """Submissions per outside client per sliding minute."""
    kiosk_per_minute: int = 60
    """Submissions per sliding minute from the kiosk, all its visitors together."""
    client_max_waiting: int = 10
    """Jobs of one outside client waiting (for approval or in the queue) at once."""


def quota_policy(show: Show) -> QuotaPolicy:
    """The quotas of ``show``."""
    policy = show.policy
    return QuotaPolicy(
        client_per_minute=policy.client_submits_per_minute,
        kiosk_per_minute=policy.kiosk_submits_per_minute,
        client_max_waiting=policy.client_max_waiting,
    )


@dataclass
class SubmitQuotas:
    """Counts each identity's submissions; :meth:`refusal` says whether to take one more."""

    policy: QuotaPolicy
    _clients: SlidingWindowLimiter = field(init=False)
    _kiosk: SlidingWindowLimiter = field(init=False)

    def __post_init__(self) -> None:
        self._clients = SlidingWindowLimiter(self.policy.client_per_minute, WINDOW_S)
        self._kiosk = SlidingWindowLimiter(self.policy.kiosk_per_minute, WINDOW_S)

    def refusal(
        self, identity: str, waiting: int, now_s: float, *, count: int = 1
    ) -> ErrorInfo | None:
        """Count a submission of ``count`` jobs (a phrase counts as its characters) of
        ``identity`` at ``now_s`` [s] (``waiting``: its jobs waiting now); None to take it, else
        why not, with when to retry."""
        if is_operator(identity):
            return None
        limit = self.policy.kiosk_per_minute if identity == KIOSK else self.policy.client_per_minute
        limiter = self._kiosk if identity == KIOSK else self._clients
        waits_s = [limiter.hit(identity, now_s) for _ in range(max(1, count))]
        wait_s = next((w for w in waits_s if w is not None), None)
        if wait_s is not None:
            return ErrorInfo(
                code="rate_limited",
                message=f"{identity} may submit {limit} a minute: "
                f"try again in {math.ceil(wait_s)} s",
            )
        if identity != KIOSK and waiting + max(1, count) > self.policy.client_max_waiting:
            return ErrorInfo(
                code="rate_limited",
                message=f"{identity} has {waiting} jobs waiting, the most a client may: "
                f"try again when one is approved or written",
            )
        return None
