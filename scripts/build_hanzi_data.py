#!/usr/bin/env python3
"""Build planner/glyphs/data/hanzi_medians.bin from the npm package hanzi-writer-data.

The package holds, per character, Make Me a Hanzi's outline strokes and stroke *medians*
(centrelines, in correct stroke order) in a 1024 grid whose y axis points UP with the font
baseline at y = 0 (the em box spans x 0..1024, y -124..900). We keep only the medians, as
integers, in an indexed store read one character at a time: see
``planner/glyphs/hanzi_store.py`` and docs/formats.md.

Usage:
    python scripts/build_hanzi_data.py            # npm pack hanzi-writer-data@2.0.1 in a temp dir
    python scripts/build_hanzi_data.py PATH       # an extracted package folder or a .tgz
    python scripts/build_hanzi_data.py --out DIR  # default planner/glyphs/data
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

PACKAGE = "hanzi-writer-data"
VERSION = "2.0.1"
DATA_NAME = "hanzi_medians.bin"
LICENSE_NAME = "LICENSE-hanzi-writer-data.txt"
REPO_ROOT = Path(__file__).resolve().parents[1]
if str(REPO_ROOT) not in sys.path:
    sys.path.insert(0, str(REPO_ROOT))

from planner.glyphs.hanzi_store import encode_store  # noqa: E402  (after the path above)

ATTRIBUTION = f"""\
Stroke data: planner/glyphs/data/{DATA_NAME}

Derived by scripts/build_hanzi_data.py from the npm package {PACKAGE}@{VERSION}
(https://github.com/chanind/hanzi-writer-data, by David Chanin), whose data comes from the
Make Me a Hanzi project (https://github.com/skishore/makemeahanzi, by Shaunak Kishore), which
extracted it from fonts by Arphic Technology Co., Ltd. ("AR PL KaitiM GB", "AR PL UKai").
Only the stroke medians (centrelines) are kept, rounded to integers and re-encoded.

This data may be redistributed and/or modified under the terms of the Arphic Public License,
reproduced unaltered below (ARPHICPL.TXT from the package).

------------------------------------------------------------------------------------------
"""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("source", nargs="?", type=Path, help="extracted package folder or .tgz")
    parser.add_argument("--out", type=Path, default=REPO_ROOT / "planner" / "glyphs" / "data")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        folder = _package_folder(args.source, Path(tmp))
        chars = read_medians(folder)
        license_text = (folder / "ARPHICPL.TXT").read_text(encoding="utf-8")
    args.out.mkdir(parents=True, exist_ok=True)
    data_path = args.out / DATA_NAME
    data_path.write_bytes(encode(chars))
    (args.out / LICENSE_NAME).write_text(ATTRIBUTION + license_text, encoding="utf-8")
    points = sum(len(s) for strokes in chars.values() for s in strokes)
    print(
        f"{len(chars)} characters, {points} points -> {data_path} "
        f"({data_path.stat().st_size} bytes)"
    )
    return 0


def _package_folder(source: Path | None, tmp: Path) -> Path:
    if source is None:
        subprocess.run(
            ["npm", "pack", f"{PACKAGE}@{VERSION}", "--silent"],
            cwd=tmp,
            check=True,
            stdout=sys.stderr,
        )
        source = next(tmp.glob(f"{PACKAGE}-*.tgz"))
    if source.is_file():
        with tarfile.open(source) as tar:
            tar.extractall(tmp / "extracted", filter="data")
        source = tmp / "extracted" / "package"
    if not (source / "ARPHICPL.TXT").is_file():
        raise SystemExit(f"{source}: no ARPHICPL.TXT, not a {PACKAGE} package folder")
    return source


def read_medians(folder: Path) -> dict[str, list[list[tuple[int, int]]]]:
    """Medians of every ``<char>.json`` file as integer points, stroke order kept."""
    chars: dict[str, list[list[tuple[int, int]]]] = {}
    for path in sorted(folder.glob("*.json")):
        char = path.stem
        if len(char) != 1:
            continue  # package.json and the like
        medians = json.loads(path.read_text(encoding="utf-8"))["medians"]
        strokes = []
        for k, median in enumerate(medians):
            points = [(_round(x), _round(y)) for x, y in median]
            points = [p for i, p in enumerate(points) if i == 0 or p != points[i - 1]]
            if len(points) < 2:
                raise SystemExit(f"{path}: stroke {k} has fewer than 2 distinct points")
            strokes.append(points)
        if not strokes:
            raise SystemExit(f"{path}: no strokes")
        chars[char] = strokes
    if not chars:
        raise SystemExit(f"{folder}: no character files")
    return chars


def _round(value: float) -> int:
    return math.floor(value + 0.5)


def encode(chars: dict[str, list[list[tuple[int, int]]]]) -> bytes:
    """The store's bytes (deterministic: same input, same bytes)."""
    meta = {
        "source": f"{PACKAGE}@{VERSION} (Make Me a Hanzi medians, Arphic Public License)",
        "grid": 1024,
        "y_min": -124,
        "y_max": 900,
    }
    return encode_store(chars, meta)


if __name__ == "__main__":
    raise SystemExit(main())
