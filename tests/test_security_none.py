"""``security: none`` is for loopback only: refused beyond it when the show file loads, and said
in red on ``skyquill up``'s terminal (issue 30)."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from cli import cmd_up
from cli.main import main
from cli.showrun import derived_show
from showfile import ShowError, load_show
from showfile.security import on_loopback

SOLO = Path(__file__).resolve().parents[1] / "shows" / "solo.yaml"


def _unsecured(tmp_path: Path, listen: str) -> Path:
    """solo.yaml with ``security: none``, its router listening on ``listen``."""
    base = load_show(SOLO)
    path, show = derived_show(
        SOLO, tmp_path, security=base.security.model_copy(update={"mode": "none"})
    )
    text = path.read_text(encoding="utf-8")
    return _written(tmp_path, text.replace(show.zenoh.router_listen[0], listen, 1))


def _written(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "unsecured.yaml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("endpoint", "local"),
    [
        ("tcp/127.0.0.1:7447", True),
        ("tcp/127.0.0.2:7447", True),
        ("tcp/[::1]:7447", True),
        ("tcp/localhost:7447#iface=lo", True),
        ("tcp/0.0.0.0:7447", False),
        ("tcp/[::]:7447", False),
        ("tcp/192.168.1.20:7447", False),
        ("udp/show-host.local:7447", False),
    ],
)
def test_loopback_endpoints(endpoint: str, local: bool) -> None:
    assert on_loopback(endpoint) is local


def test_an_unsecured_show_listening_beyond_loopback_is_refused_naming_file_line_field(
    tmp_path: Path,
) -> None:
    path = _unsecured(tmp_path, "tcp/0.0.0.0:7447")
    line = next(n for n, text in enumerate(path.read_text().splitlines(), 1) if "0.0.0.0" in text)
    with pytest.raises(ShowError) as caught:
        load_show(path)
    (problem,) = caught.value.problems  # type: ignore[attr-defined]
    said = str(problem)
    assert said.startswith(f"{path}:{line}: zenoh.router_listen[0]: tcp/0.0.0.0:7447 reaches")
    assert "security is none" in said and "\n" not in said


def test_an_unsecured_show_on_loopback_loads(tmp_path: Path) -> None:
    assert load_show(_unsecured(tmp_path, "tcp/127.0.0.1:7447")).security.mode == "none"


@pytest.mark.parametrize("terminal", [True, False])
def test_up_says_security_none_on_its_terminal_in_red(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    terminal: bool,
) -> None:
    (tmp_path / "mtls").mkdir()
    path, _ = derived_show(SOLO, tmp_path / "mtls")
    unsecured = _unsecured(tmp_path, "tcp/127.0.0.1:7447")
    started: list[str] = []

    def supervise(args: argparse.Namespace, *_: object, **__: object) -> None:
        started.append(str(args.show))  # the warning comes before any process starts

    monkeypatch.setattr(cmd_up, "_supervise", supervise)
    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.setattr("sys.stderr.isatty", lambda: terminal)
    assert main(["up", str(unsecured), "--headless", "--no-kiosk"]) == 0
    said = capsys.readouterr().err
    assert "runs with security: none" in said
    assert said.startswith(cmd_up.RED) is terminal and (cmd_up.RESET in said) is terminal
    assert main(["up", str(path), "--headless", "--no-kiosk"]) == 0  # mtls: no warning
    assert "security: none" not in capsys.readouterr().err
    assert started == [str(unsecured), str(path)]
