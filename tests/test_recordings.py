"""Recordings of a long show: cut into whole MCAP parts, the oldest removed past the budget."""

from __future__ import annotations

import os
import subprocess
import threading
import time
from pathlib import Path

import msgspec
import pytest
from mcap.reader import make_reader

from bus import recorder as recorder_module
from bus.keys import ShowKeys
from bus.messages import SubmitReply, SubmitRequest
from bus.recorder import McapRecorder, message_type_for_topic
from orchestrator.recordings import prune_recordings

KEYS = ShowKeys("long")


def _messages(path: Path) -> list[str]:
    with path.open("rb") as f:
        return [channel.topic for _, channel, _ in make_reader(f).iter_messages()]


def test_a_recording_is_cut_into_parts_each_readable_on_its_own(tmp_path: Path) -> None:
    finished: list[tuple[Path, Path]] = []
    recorder = McapRecorder(
        tmp_path / "long-run.mcap",
        KEYS,
        max_file_bytes=20_000,
        on_part_done=lambda done, begun: finished.append((done, begun)),
        chunk_size_bytes=4096,
    )
    for k in range(400):  # one channel per job key, as jobs/<id> publications make
        payload = msgspec.json.encode({"job_id": f"j{k}", "note": os.urandom(200).hex()})
        recorder.record(KEYS.job(f"j{k}"), payload)
    recorder.close()
    parts = [tmp_path / "long-run.mcap", *sorted(tmp_path.glob("long-run-*.mcap"))]
    assert len(parts) == recorder.parts >= 3
    assert [done for done, _ in finished] == parts[:-1]
    assert [begun for _, begun in finished] == parts[1:]
    assert parts[1].name == "long-run-002.mcap"
    topics = [topic for part in parts for topic in _messages(part)]
    assert topics == [KEYS.job(f"j{k}") for k in range(400)]  # nothing lost, in order
    channels_per_part = [len(set(_messages(part))) for part in parts]
    assert max(channels_per_part) < 400  # each part's index holds only its own jobs


def test_a_part_also_ends_past_its_chunk_count_with_messages_that_compress_away(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Hostile payloads compress to nothing: parts bounded by bytes alone would grow their index
    (one entry per chunk) without end; the chunk count ends them too."""
    monkeypatch.setattr(recorder_module, "MAX_CHUNKS_PER_PART", 10)
    with McapRecorder(tmp_path / "r.mcap", KEYS, max_file_bytes=10**9,
                      chunk_size_bytes=4096) as recorder:  # fmt: skip
        for k in range(100):  # each a chunk of its own: 8 kB of one letter
            recorder.record(KEYS.events, msgspec.json.encode({"k": k, "pad": "x" * 8000}))
    parts = sorted(tmp_path.glob("r*.mcap"))
    assert recorder.parts == len(parts) >= 9  # 100 chunks, 10 a part
    assert sum(len(_messages(part)) for part in parts) == 100  # every message, in whole parts


def test_messages_past_the_queue_budget_are_dropped_and_counted(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(recorder_module, "MAX_QUEUED_BYTES", 50_000)
    gate = threading.Event()
    with McapRecorder(tmp_path / "r.mcap", KEYS) as recorder:
        monkeypatch.setattr(recorder, "_write", lambda *_: gate.wait(10.0))  # a stalled writer
        try:
            for _ in range(100):  # 10 kB each: 5 fit the budget (6: the writer took one)
                recorder.record(KEYS.events, msgspec.json.encode({"pad": "x" * 9_990}))
            assert recorder.dropped in (94, 95)
        finally:
            gate.set()


def test_only_json_payloads_are_recorded_the_others_counted(tmp_path: Path) -> None:
    recorder = McapRecorder(tmp_path / "mixed.mcap", KEYS)
    payloads = [b'{"a": 1}', b"not json", b'{"a": ', b"\xff\xfe", b"NaN", b"", b"[1, 2]"]
    for k, payload in enumerate(payloads):
        recorder.record(KEYS.job(f"j{k}"), payload)
    recorder.close()
    assert (recorder.messages, recorder.skipped) == (2, 5)
    assert _messages(tmp_path / "mixed.mcap") == [KEYS.job("j0"), KEYS.job("j6")]


def _recording(directory: Path, name: str, size: int, age_s: float) -> Path:
    path = directory / name
    path.write_bytes(b"x" * size)
    stamp = 1_000_000.0 - age_s
    os.utime(path, (stamp, stamp))
    return path


def test_the_oldest_recordings_go_first_down_to_the_budget(tmp_path: Path) -> None:
    oldest = _recording(tmp_path, "long-a.mcap", 400, age_s=50)
    old = _recording(tmp_path, "long-b.mcap", 400, age_s=40)
    kept = _recording(tmp_path, "long-c.mcap", 400, age_s=30)
    finished = _recording(tmp_path, "long-d.mcap", 400, age_s=20)
    begun = _recording(tmp_path, "long-d-002.mcap", 10, age_s=0)
    other = _recording(tmp_path, "other-a.mcap", 5000, age_s=90)  # another show's
    removed = prune_recordings(tmp_path, "long", 900, keep=(finished, begun))
    assert removed == [oldest, old]
    assert {p.name for p in tmp_path.iterdir()} == {
        kept.name,
        finished.name,
        begun.name,
        other.name,
    }


def test_the_kept_parts_stay_even_over_budget(tmp_path: Path) -> None:
    finished = _recording(tmp_path, "long-a.mcap", 400, age_s=20)
    begun = _recording(tmp_path, "long-a-002.mcap", 10, age_s=0)
    assert prune_recordings(tmp_path, "long", 100, keep=(finished, begun)) == []


def test_every_submit_key_is_recorded_under_its_schema() -> None:
    keys = ShowKeys("s")
    for key in (keys.submit, keys.submit_as("kiosk"), keys.submit_as("submitter@booth")):
        assert message_type_for_topic(keys, key + "#request") is SubmitRequest
        assert message_type_for_topic(keys, key + "#reply") is SubmitReply


def test_a_full_disk_stops_the_recording_not_the_recorder_and_it_resumes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    if os.geteuid() != 0:
        pytest.skip("needs root to mount a disk of its own (tmpfs)")
    disk = tmp_path / "disk"
    disk.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=4m", "tmpfs", str(disk)], check=True)
    monkeypatch.setattr(recorder_module, "RETRY_AFTER_FULL_S", 0.2)
    noise = [msgspec.json.encode({"noise": os.urandom(3000).hex()}) for _ in range(3000)]
    try:
        with McapRecorder(disk / "r.mcap", KEYS, chunk_size_bytes=64 * 1024) as rec:
            for payload in noise:  # 18 MB of random hex (9 MB compressed): past the 4 MB disk
                rec.record(KEYS.events, payload)
            rec.flush()
            deadline = time.monotonic() + 10.0
            while rec.dropped == 0 and time.monotonic() < deadline:
                time.sleep(0.05)
            assert rec.dropped > 0  # the disk filled, and the recorder lives on
            for path in disk.iterdir():
                path.unlink()  # room again
            time.sleep(0.3)
            rec.record(KEYS.events, noise[0])
            rec.record(KEYS.events, noise[1])
        parts = sorted(disk.iterdir())
        assert parts and _messages(parts[-1]) == [KEYS.events] * 2  # a new part, whole
    finally:
        subprocess.run(["umount", "--lazy", str(disk)], check=False)
