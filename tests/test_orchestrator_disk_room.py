"""A full disk: new characters are refused in one clear line, and nothing taken is lost
(``orchestrator/disk_room.py``)."""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
from test_orchestrator_service import (
    RunningOrchestrator,
    _snapshot,
    _snapshot_when_up,
    _submit,
    client,  # noqa: F401 (fixture)
    endpoint,  # noqa: F401 (fixture)
    make_show,
)
from test_orchestrator_store import _job

from bus.keys import ShowKeys
from bus.messages import SubmitRequest
from bus.session import Session
from orchestrator.disk_room import DiskReserve, storage_full
from orchestrator.store import JobStore, StoreError

DISK_BYTES = 16 * 1024**2


def test_room_is_the_free_space_of_the_databases_disk(tmp_path: Path) -> None:
    database = tmp_path / "show.sqlite3"
    free_bytes = shutil.disk_usage(tmp_path).free
    assert storage_full(database, free_bytes / 2) is None
    assert storage_full(database, 0.0) is None  # 0: never refused
    full = storage_full(database, free_bytes + 1e12)
    assert full is not None and full.code == "storage_full"
    assert "no new character is taken until room is made" in full.message
    assert "\n" not in full.message


@pytest.fixture()
def own_disk(tmp_path: Path) -> Iterator[Path]:
    """A 16 MB tmpfs of the test's own (root)."""
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("needs root to mount a disk of its own (tmpfs)")
    folder = tmp_path / "disk"
    folder.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={DISK_BYTES}", "tmpfs", str(folder)],
                   check=True)  # fmt: skip
    try:
        yield folder
    finally:
        subprocess.run(["umount", "--lazy", str(folder)], check=False)


def _fill(folder: Path, leave_bytes: int = 0) -> Path:
    """Take all but ``leave_bytes`` of the disk at ``folder`` (0: to the last byte)."""
    ballast = folder / "ballast"
    fd = os.open(ballast, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    try:
        for size in (1 << 20, 4096, 1):
            while shutil.disk_usage(folder).free >= leave_bytes + size:
                try:
                    os.write(fd, b"\0" * size)
                except OSError:
                    break
    finally:
        os.close(fd)
    return ballast


def test_a_write_that_finds_the_disk_full_gives_the_reserve_up_and_is_kept(
    own_disk: Path,
) -> None:
    database = own_disk / "show.sqlite3"
    reserve = DiskReserve(database, size_bytes=2 * 1024**2)
    assert reserve.make() and reserve.held
    with JobStore(database, reserve) as store:
        store.save([_job("j1", 1)])
        ballast = _fill(own_disk)
        assert shutil.disk_usage(own_disk).free == 0
        store.save([_job(f"j{n}", n) for n in range(2, 400)])  # ~100 kB: the WAL must grow
        assert store.reserve_given_up and not reserve.held
        assert not reserve.make()  # no room for it yet
        ballast.unlink()
        assert reserve.make() and reserve.held
    with JobStore(database) as store:
        assert len(store.load().jobs) == 399  # every write kept


def test_without_a_reserve_a_full_disk_stops_the_store_with_one_line(own_disk: Path) -> None:
    database = own_disk / "show.sqlite3"
    with JobStore(database) as store:
        store.save([_job("j1", 1)])
        _fill(own_disk)
        with pytest.raises(StoreError, match=r"show\.sqlite3: .*(full|I/O)"):
            store.save([_job(f"j{n}", n) for n in range(2, 400)])


def test_a_nearly_full_disk_refuses_new_characters_and_keeps_those_taken(
    own_disk: Path,
    endpoint: str,  # noqa: F811
    client: Session,  # noqa: F811
) -> None:
    _, show = make_show(own_disk, "diskfull", endpoint)
    storage = show.storage.model_copy(update={"min_free_mb": 4.0, "record": False})
    show = show.model_copy(update={"storage": storage})
    keys = ShowKeys(show.show_id)
    with RunningOrchestrator(show):
        _snapshot_when_up(client, keys)
        taken = _submit(client, keys, SubmitRequest(text="L"))
        assert taken.ok
        ballast = _fill(own_disk, leave_bytes=2 * 1024**2)
        refused = _submit(client, keys, SubmitRequest(text="M"))
        assert not refused.ok and refused.error is not None
        assert refused.error.code == "storage_full", refused.error
        assert "MB free" in refused.error.message
        assert [j.job_id for j in _snapshot(client, keys).jobs] == [taken.job_id]
        ballast.unlink()
        again = _submit(client, keys, SubmitRequest(text="M"))
        assert again.ok
    with RunningOrchestrator(show):  # restarted: what was acknowledged is all there
        jobs = {j.job_id for j in _snapshot_when_up(client, keys).jobs}
        assert jobs == {taken.job_id, again.job_id}
