"""QR codes of ticket links, as small SVG documents (segno: a pure-Python QR encoder)."""

from __future__ import annotations

import io

import segno


def qr_svg(url: str) -> bytes:
    """An SVG QR code of ``url`` (error correction M, 4 px modules, quiet zone of 4 modules)."""
    code = segno.make(url, error="m", micro=False)
    out = io.BytesIO()
    code.save(out, kind="svg", scale=4, border=4, xmldecl=False, title="QR code of " + url)
    return out.getvalue()
