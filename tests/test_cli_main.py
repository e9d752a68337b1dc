"""The ``skyquill`` command finds its subcommands and fails clearly on unknown ones."""

from __future__ import annotations

import pytest

from cli.main import _discover, main


def test_every_subcommand_module_declares_name_and_help() -> None:
    commands = _discover()
    for name, (module_name, help_line) in commands.items():
        assert module_name.startswith("cli.cmd_"), name
        assert help_line, f"{module_name} has no HELP line"


def test_unknown_subcommand_exits_with_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["no-such-command"])
    assert exit_info.value.code == 2
    assert "invalid choice" in capsys.readouterr().err


def test_subcommand_named_after_its_file_is_found_directly() -> None:
    from cli.main import _named_module

    plan = _named_module("plan")
    assert plan is not None and plan.__name__ == "cli.cmd_plan"
    stop = _named_module("stop")  # cmd_stop.py is "down", "stop" its alias
    assert stop is not None and stop.__name__ == "cli.cmd_stop"
    assert _named_module("down") is None  # no cmd_down.py: found by discovery instead
    assert _named_module("../main") is None
    assert _discover()["down"][0] == "cli.cmd_stop"


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (["fly", "--text", "I", "--wind", "abc"], "skyquill fly: argument --wind: not a number"),
        (["fly", "--text", "I", "--no-such-flag"], "unrecognized arguments: --no-such-flag"),
        (["plan"], "one of the arguments --strokes --text is required"),
        (["no-such-command"], "skyquill: argument COMMAND: invalid choice"),
    ],
)
def test_a_bad_flag_is_one_line_naming_it_and_the_way_out(
    argv: list[str], named: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Not argparse's usage block above the error: one line, the flag, ``--help`` to read."""
    with pytest.raises(SystemExit) as exited:
        main(argv)
    assert exited.value.code == 2
    err = capsys.readouterr().err
    prog = "skyquill" if argv[0] == "no-such-command" else f"skyquill {argv[0]}"
    assert err.count("\n") == 1 and "usage:" not in err
    assert named in err and err.rstrip().endswith(f"(see {prog} --help)")


def test_help_is_still_argparse_usage(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["fly", "--help"])
    assert exited.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: skyquill fly") and "--wind" in out
