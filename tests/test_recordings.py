"""Recordings of a long show: cut into whole MCAP parts, the oldest removed past the budget."""

from __future__ import annotations

import os
from pathlib import Path

import msgspec
from mcap.reader import make_reader

from bus.keys import ShowKeys
from bus.recorder import McapRecorder
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
