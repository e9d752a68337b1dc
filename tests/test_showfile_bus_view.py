"""The light bus view of a show file (``skyquill status``) agrees with the full loader, knows every
field of the sections it reads, and leaves what it does not vouch for to the loader."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from showfile import SecuritySettings, ZenohSettings, dump_show, load_show
from showfile.bus_view import (
    HostView,
    SecurityView,
    ShowBus,
    ZenohView,
    read_bus_view,
)
from showfile.services import ZenohHost
from trust.files import IdentityFiles
from trust.settings import companion_routers, identities, secured

SHOWS = sorted((Path(__file__).resolve().parents[1] / "shows").glob("*.yaml"))


def _bus_part(show: ShowBus) -> dict[str, Any]:
    """Everything a session of the show reads, as plain values."""
    z = show.zenoh
    hosts = {
        name: (
            h.router_listen,
            h.connect,
            h.router_connect,
            h.services,
            h.vehicles,
            h.local_connect,
        )
        for name, h in z.hosts.items()
    }
    return {
        "show_id": show.show_id,
        "vehicles": [v.id for v in show.vehicles],
        "zenoh": (
            z.router_listen,
            z.connect,
            z.multicast_scouting,
            z.router_connect,
            z.peer_listen,
            dict(z.extra),
            z.open_timeout_s,
            hosts,
        ),
        "mode": show.security.mode,
        "keys_dir": show.keys_dir,
        "source_path": show.source_path,
        "identities": identities(show),
        "companion_routers": companion_routers(show),
    }


@pytest.mark.parametrize("path", SHOWS, ids=lambda p: p.name)
def test_view_of_every_shipped_show_is_the_loaders(path: Path, tmp_path: Path) -> None:
    view, show = read_bus_view(path), load_show(path)
    assert view is not None
    assert _bus_part(view) == _bus_part(show)
    for name in ("cert", "key", "ca"):
        (tmp_path / name).touch()
    files = IdentityFiles("operator", tmp_path / "cert", tmp_path / "key", tmp_path / "ca")
    for router in (False, True):
        assert secured(view, files, router=router) == secured(show, files, router=router)


def test_view_of_a_dumped_show_with_its_defaults_written_out(tmp_path: Path) -> None:
    show = load_show(SHOWS[0])
    path = tmp_path / "show.yaml"
    dump_show(show, path)
    view = read_bus_view(path)
    assert view is not None and _bus_part(view) == _bus_part(load_show(path))


@pytest.mark.parametrize("security", [{}, {"keys_dir": "k"}])
def test_keys_are_found_from_the_show_files_folder_not_the_working_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, security: dict[str, Any]
) -> None:
    """Issue 31, for ``skyquill status``: the keys beside the database the show file names
    (``../out/solo`` from ``shows/``), or its own ``keys_dir``, both from the file's folder."""
    root = tmp_path.resolve()
    (root / "shows").mkdir()
    (root / "elsewhere").mkdir()
    doc = {**_minimal(), "security": {"mode": "mtls", **security}}
    path = root / "shows" / "solo.yaml"
    path.write_text(yaml.safe_dump(doc), encoding="utf-8")
    monkeypatch.chdir(root / "elsewhere")
    view = read_bus_view(Path("..") / "shows" / "solo.yaml")
    assert view is not None
    wanted = root / "shows" / "k" if security else root / "out" / "solo" / "keys"
    assert view.keys_dir == wanted == load_show(path).keys_dir


@pytest.mark.parametrize(
    ("view_class", "model_class"),
    [(ZenohView, ZenohSettings), (HostView, ZenohHost), (SecurityView, SecuritySettings)],
)
def test_view_knows_every_field_of_the_models(view_class: type, model_class: Any) -> None:
    """A field added to a model must be added to the view (or the view would ignore it)."""
    assert set(view_class.__dataclass_fields__) == set(model_class.model_fields)


def test_view_defaults_are_the_models() -> None:
    for view, model in ((ZenohView(), ZenohSettings()), (SecurityView(), SecuritySettings())):
        for name in view.__dataclass_fields__:
            assert getattr(view, name) == getattr(model, name), name


def _minimal() -> dict[str, Any]:
    return yaml.safe_load((SHOWS[0].parent / "solo.yaml").read_text())


@pytest.mark.parametrize(
    "change",
    [
        {"zenoh": {"multicast_scouting": "yes"}},  # the models coerce it: theirs to say
        {"zenoh": {"router_listen": "tcp/127.0.0.1:7447"}},  # a string, not a list
        {"zenoh": {"no_such_field": 1}},
        {"zenoh": {"open_timeout_s": -1.0}},
        {"zenoh": {"connect": []}},  # nowhere to connect with scouting off
        {"zenoh": {"hosts": {"a": {"router_listen": ["tcp/0.0.0.0:7447"]}}}},  # no ground station
        {"security": {"mode": "tls"}},
        {"vehicles": [{"id": "operator"}]},  # a role's name
        {"show_id": "bad id"},
        {"source_path": "x.yaml"},
        {"storage": {"database": 5}},  # not a path
        {"storage": "show.sqlite3"},
    ],
)
def test_what_the_view_does_not_vouch_for_is_left_to_the_loader(
    tmp_path: Path, change: dict[str, Any]
) -> None:
    doc = {**_minimal(), **change}
    path = tmp_path / "show.yaml"
    path.write_text(yaml.safe_dump(doc), encoding="utf-8")
    assert read_bus_view(path) is None


def test_duplicate_key_missing_file_and_non_mapping_are_left_to_the_loader(
    tmp_path: Path,
) -> None:
    path = tmp_path / "show.yaml"
    text = (SHOWS[0].parent / "solo.yaml").read_text()
    path.write_text(text + "\nshow_id: again\n", encoding="utf-8")
    assert read_bus_view(path) is None
    assert read_bus_view(tmp_path / "missing.yaml") is None
    path.write_text("- a list\n", encoding="utf-8")
    assert read_bus_view(path) is None
