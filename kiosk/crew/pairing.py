"""Crew phones paired with the kiosk by a code the operator hands out (``skyquill crew SHOW
--pair NAME``): the code opens the crew page once, on one phone, within :data:`CODE_TTL_S`.

A phone never holds a certificate: the kiosk process holds the crew's (``trust/acl.py``) and
speaks for the phones it paired, naming each in the commands it sends (``crew (deck-1)`` in the
event log). Pairing turns the code into a random token the phone keeps in a cookie; the file
keeps only hashes of codes and tokens (``<keys_dir>/crew-phones.json``, 0600), and both the CLI
and the kiosk change it under a lock, so ``--unpair NAME`` shuts a lost phone out at its next
request. :class:`PairingBook` is the pure part; :class:`PairingFile` reads and writes it.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
import re
import secrets
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TypeVar

from kiosk.errors import KioskError

CODE_ALPHABET = "ABCDEFGHJKMNPQRSTUVWXYZ23456789"
"""No 0/O, 1/I/L: read aloud or off a screen without doubt (31 signs, 8 of them: ~40 bits)."""
CODE_LENGTH = 8
CODE_TTL_S = 600.0
"""A code opens the page within ten minutes of its printing, once."""
PHONE_TTL_S = 24 * 3600.0
"""A paired phone stays paired for a show day; then it needs a new code."""
NAME_RE = re.compile(r"^[A-Za-z0-9_-]{1,32}$")
"""A phone's name, as the event log shows it."""
T = TypeVar("T")


class PairingError(KioskError):
    """The phones' file cannot be read or written, or a name is not a phone's name."""


def _digest(secret: str) -> str:
    return hashlib.sha256(secret.encode()).hexdigest()


def normal_code(typed: str) -> str:
    """A code as typed (any case, dashes, spaces) in the form it was made."""
    return re.sub(r"[^A-Z0-9]", "", typed.upper())


def shown_code(code: str) -> str:
    """``ABCD2345`` -> ``ABCD-2345``."""
    return f"{code[:4]}-{code[4:]}"


@dataclass(frozen=True)
class PairingBook:
    """Open codes and paired phones, by the hash of their secret."""

    codes: dict[str, tuple[str, float]] = field(default_factory=dict)
    """Hash of a code -> the phone's name and when the code expires, Unix time [s]."""
    phones: dict[str, tuple[str, float]] = field(default_factory=dict)
    """Hash of a phone's token -> its name and when it was paired, Unix time [s]."""

    def offered(self, name: str, code: str, now_s: float) -> PairingBook:
        """With a new code for ``name`` (any earlier open code of ``name`` withdrawn)."""
        if not NAME_RE.match(name):
            raise PairingError(f"{name!r} is not a phone's name: letters, digits, - and _ (1-32)")
        codes = {h: c for h, c in self.codes.items() if c[0] != name and c[1] > now_s}
        codes[_digest(code)] = (name, now_s + CODE_TTL_S)
        return replace(self, codes=codes)

    def paired(self, code: str, token: str, now_s: float) -> tuple[PairingBook, str | None]:
        """With ``token`` paired for the code's phone (the code used up); the phone's name, or
        None when the code is unknown, used or expired (nothing changes then)."""
        offer = self.codes.get(_digest(normal_code(code)))
        if offer is None or offer[1] <= now_s:
            return self, None
        name = offer[0]
        codes = {h: c for h, c in self.codes.items() if c[0] != name}
        phones = {**self.phones, _digest(token): (name, now_s)}
        return replace(self, codes=codes, phones=phones), name

    def holder(self, token: str, now_s: float) -> str | None:
        """The name of the phone paired with ``token`` (None: none, unpaired, or too old)."""
        phone = self.phones.get(_digest(token))
        if phone is None or now_s - phone[1] > PHONE_TTL_S:
            return None
        return phone[0]

    def unpaired(self, name: str) -> tuple[PairingBook, int]:
        """Without ``name``'s phones and open codes; how many phones were shut out."""
        phones = {h: p for h, p in self.phones.items() if p[0] != name}
        codes = {h: c for h, c in self.codes.items() if c[0] != name}
        return replace(self, codes=codes, phones=phones), len(self.phones) - len(phones)

    def names(self, now_s: float) -> list[str]:
        """The phones paired now, by name."""
        return sorted({name for name, since_s in self.phones.values()
                       if now_s - since_s <= PHONE_TTL_S})  # fmt: skip


def new_code() -> str:
    return "".join(secrets.choice(CODE_ALPHABET) for _ in range(CODE_LENGTH))


def new_token() -> str:
    return secrets.token_urlsafe(32)


class PairingFile:
    """The :class:`PairingBook` of a show on disk, read and changed under a lock."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)

    @contextlib.contextmanager
    def _locked(self) -> Iterator[None]:
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            lock = self.path.with_name(self.path.name + ".lock")
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o600)
        except OSError as exc:
            raise PairingError(f"{self.path}: cannot lock the crew's phones: {exc}") from exc
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            yield
        finally:
            os.close(fd)

    def _read(self) -> PairingBook:
        try:
            data = json.loads(self.path.read_text(encoding="utf-8"))
            codes = {h: (str(n), float(t)) for h, (n, t) in data["codes"].items()}
            phones = {h: (str(n), float(t)) for h, (n, t) in data["phones"].items()}
        except FileNotFoundError:
            return PairingBook()
        except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
            raise PairingError(f"{self.path}: not the crew's phones: {exc}") from exc
        return PairingBook(codes, phones)

    def _write(self, book: PairingBook) -> None:
        data = {"codes": book.codes, "phones": book.phones}
        partial = self.path.with_name(self.path.name + ".partial")
        try:
            fd = os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
            with os.fdopen(fd, "w", encoding="utf-8") as out:
                json.dump(data, out, indent=1)
            os.replace(partial, self.path)
        except OSError as exc:
            raise PairingError(f"{self.path}: cannot write the crew's phones: {exc}") from exc

    def read(self) -> PairingBook:
        with self._locked():
            return self._read()

    def change(self, how: Callable[[PairingBook], tuple[PairingBook, T]]) -> T:
        """Apply ``how`` to the book on disk and keep its new book; returns its answer."""
        with self._locked():
            book, answer = how(self._read())
            self._write(book)
            return answer
