"""Every link of the README and of docs/ leads somewhere: a file of the tree and, with
``#anchor``, a heading of that file (GitHub's anchors)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^```.*?^```", re.M | re.S)


def anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation but ``-`` and ``_`` dropped,
    spaces as ``-``."""
    text = heading.lower().replace("`", "")
    return "".join(c for c in text if c.isalnum() or c in " -_").replace(" ", "-")


def anchors_of(page: Path) -> set[str]:
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    return {anchor(line.lstrip("#").strip()) for line in text.splitlines() if line.startswith("#")}


def links_of(page: Path) -> list[str]:
    return LINK.findall(FENCE.sub("", page.read_text(encoding="utf-8")))


def test_github_anchors_are_made_as_github_makes_them() -> None:
    assert anchor("Real autopilot SITL") == "real-autopilot-sitl"
    assert anchor("`zenoh.hosts.<name>` (`ZenohHost`)") == "zenohhostsname-zenohhost"
    assert anchor("`mavlink_sim` (`MavlinkSimSettings`)") == "mavlink_sim-mavlinksimsettings"


def test_every_relative_link_resolves_to_a_file_and_heading() -> None:
    broken = []
    for page in PAGES:
        for target in links_of(page):
            if re.match(r"[a-z]+:", target):  # http:, https:, mailto:
                continue
            path_part, _, fragment = target.partition("#")
            file = (page.parent / path_part).resolve() if path_part else page
            if not file.exists():
                broken.append(f"{page.name}: {target} (no such file)")
            elif fragment and file.suffix == ".md" and fragment not in anchors_of(file):
                broken.append(f"{page.name}: {target} (no such heading)")
    assert not broken, "\n".join(broken)


def test_the_readme_points_at_every_guide() -> None:
    readme_links = set(links_of(ROOT / "README.md"))
    for page in PAGES[1:]:
        assert any(link.split("#")[0] == f"docs/{page.name}" for link in readme_links), page.name
