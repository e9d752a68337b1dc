"""Who is who on a show's bus: a show CA, one certificate per process, generated access control.

- ``trust.pki``: the show's certificate authority and the certificates it issues (files, 0600).
- ``trust.acl``: the Zenoh ``access_control`` section of a show, default deny (pure).
- ``trust.settings``: the bus settings of one identity (TLS files, endpoints, ACL on the router).
- ``trust.hosts``: a show across machines: the host each identity runs on, its endpoints there.
- ``trust.clients``: the outside clients issued and revoked (the router re-reads it live).

Identities are certificate common names: ``router``, ``orchestrator``, ``kiosk``, ``operator``
(console and CLI), ``crew`` (the kiosk's crew page: sheets and batteries only), each vehicle's
id, ``router@<host>`` for the router of each companion host of a show across machines, and
``<role>@<name>`` for each outside client (``operator@alice``, ``submitter@booth``,
``watcher@press``).
"""
