"""Where the files a show file names are: its relative paths are read from the show file's own
folder, as docker-compose, Ansible and kustomize read theirs, so that the same show file means the
same database, recordings and keys from whatever directory ``skyquill`` is run (issue 31:
``skyquill status /abs/show.yaml`` run elsewhere looked for the keys in that directory).

Plain Python (no pydantic): :class:`showfile.Show` and the light :mod:`showfile.bus_view` both
resolve their paths here, so the two cannot disagree.
"""

from __future__ import annotations

import os
from pathlib import Path


def resolve(source_path: Path | None, path: Path) -> Path:
    """``path`` as the show file at ``source_path`` names it: a relative one joined to the file's
    folder, made absolute and its ``..`` removed as text (docker-compose's rule; a shipped show's
    ``../out/solo`` is the checkout's ``out/solo``). An absolute ``path``, or a show built in
    memory (``source_path`` None: tests' ``parse_show``), is left as it is: relative to the
    working directory."""
    if source_path is None or path.is_absolute():
        return path
    return Path(os.path.abspath(source_path.parent / path))


def database_path(source_path: Path | None, show_id: str, database: Path | None) -> Path:
    """The SQLite file of the show: ``storage.database``, by default ``out/<show_id>/show.sqlite3``
    beside the show file. Job files, logs and run files go in its folder."""
    return resolve(source_path, database or Path("out") / show_id / "show.sqlite3")


def keys_dir(
    source_path: Path | None, show_id: str, keys: Path | None, database: Path | None
) -> Path:
    """The show's CA, certificates and private keys: ``security.keys_dir``, by default ``keys``
    in the database's folder. The show file already places its database (every shipped show in
    the checkout's ``out/<show_id>/``), and the keys belong with the rest of the show's state
    there, not in a second place a show file would have to name."""
    if keys is not None:
        return resolve(source_path, keys)
    return database_path(source_path, show_id, database).parent / "keys"
