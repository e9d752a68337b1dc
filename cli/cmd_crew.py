"""``skyquill crew SHOW.yaml --pair NAME``: a one-time code that pairs a crew phone with the
kiosk's crew page (``/crew``) for a show day; ``--unpair NAME`` shuts that phone out at its next
request; ``--list`` names the phones paired now (``kiosk/crew/pairing.py``).

A phone never holds a certificate: the kiosk holds the crew's (``crew``, which may confirm fresh
sheets and battery swaps and nothing else) and names the phone beside it in the event log."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

NAME = "crew"
HELP = "Pair a crew phone with the kiosk's crew page (a one-time code), unpair one, or list them."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    which = parser.add_mutually_exclusive_group(required=True)
    which.add_argument("--pair", metavar="NAME", help="print a code that pairs the phone NAME")
    which.add_argument("--unpair", metavar="NAME", help="shut the phone NAME out")
    which.add_argument("--list", action="store_true", help="the phones paired now")


def run(args: argparse.Namespace) -> int:
    from kiosk.crew.pairing import (
        CODE_TTL_S,
        PairingError,
        PairingFile,
        new_code,
        shown_code,
    )
    from kiosk.settings import crew_phones_path
    from showfile import ShowError, load_show

    try:
        show = load_show(args.show)
    except ShowError as exc:
        print(f"skyquill crew: {exc}", file=sys.stderr)
        return 2
    phones, now_s = PairingFile(crew_phones_path(show.keys_dir)), time.time()
    try:
        if args.pair:
            code = new_code()
            phones.change(lambda book: (book.offered(args.pair, code, now_s), None))
            minutes = round(CODE_TTL_S / 60)
            print(f"{shown_code(code)}  (phone {args.pair}: once, within {minutes} minutes, on "
                  f"the kiosk's page /crew, port {show.kiosk.port})")  # fmt: skip
        elif args.unpair:
            gone = phones.change(lambda book: book.unpaired(args.unpair))
            print(f"{args.unpair}: {gone} phone(s) shut out, its open codes withdrawn")
        else:
            print("\n".join(phones.read().names(now_s)) or "no phone is paired")
    except PairingError as exc:
        print(f"skyquill crew: {exc}", file=sys.stderr)
        return 1
    return 0
