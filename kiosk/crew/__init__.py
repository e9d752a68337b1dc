"""The crew's page on the kiosk's server: boards waiting for a sheet, vehicles waiting for a
battery, each confirmed with one tap, under the crew's own identity (never the public's).

- ``tasks``: what the crew has to do, from the fleet snapshot (pure);
- ``pairing``: phones paired by a code the operator hands out (``skyquill crew``);
- ``link``: the crew's Zenoh session (its own certificate) and its confirmations;
- ``routes``: ``/crew`` and ``/crew/api/...``.
"""
