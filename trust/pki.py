"""The show's certificate authority and the certificates it issues (the ``cryptography`` package).

Layout of a show's keys folder (``show.keys_dir``; private keys 0600, folders 0700)::

    ca.pem  ca.key                  the show CA (ECDSA P-256, 5 years)
    <identity>/cert.pem  key.pem    one per service and per vehicle (common name = identity)
    clients/<name>/cert.pem key.pem ca.pem   outside clients (common name = <role>@<name>)
    clients.json                    the outside clients admitted and revoked (trust/clients.py)

Certificates by role: only a router's certificate may serve. It carries server and client
authentication (a companion router also joins the ground router) and the routers' host names
(from the show's endpoints), which clients verify on connecting. Every other identity's
certificate is for client authentication only, without names: rustls (Zenoh's TLS) refuses it
as a server's, so a stolen vehicle's or client's key cannot pose as the router. Every
certificate is signed by the CA and valid for one year.

A CA is marked (:data:`CA_PROFILE`) as issuing by role. A keys folder whose CA lacks the mark was
made by an older skyquill, whose every certificate could serve: re-issuing its own files would
leave copies of the old ones (outside clients, companion hosts) able to pose as the router, so
it is refused with what to do (a new CA) rather than used. Likewise an outside client issued
before clients had names of their own (its common name was its role): an operator's was then the
console's own identity, and can be shut out by no access rule, so a keys folder holding one is
refused (:func:`check_old_clients`); a client holding an old folder is told to have it issued
again (:func:`client_identity`).
"""

from __future__ import annotations

import datetime
import ipaddress
import os
from collections.abc import Iterable
from pathlib import Path

from cryptography import x509
from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

from trust.clients import client_common_name
from trust.files import IdentityFiles, KeysError, identity_files
from trust.hosts import is_router

__all__ = [
    "CA_PROFILE",
    "IdentityFiles",
    "KeysError",
    "check_old_clients",
    "client_files",
    "client_identity",
    "ensure_ca",
    "identity_files",
    "is_valid",
    "issue",
]

CA_LIFETIME = datetime.timedelta(days=5 * 365)
CERT_LIFETIME = datetime.timedelta(days=365)
CLOCK_SKEW = datetime.timedelta(minutes=10)
CA_PROFILE = "certificates by role"
"""Organisational unit of a show CA that gives server authentication to routers only."""
_ROUTER_USAGES = (ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH)
_CLIENT_USAGES = (ExtendedKeyUsageOID.CLIENT_AUTH,)


def client_files(keys_dir: Path, name: str, role: str) -> IdentityFiles:
    """Paths of an outside client's identity: a folder it can carry away (with the CA cert)."""
    folder = Path(keys_dir) / "clients" / name
    return IdentityFiles(
        client_common_name(name, role), folder / "cert.pem", folder / "key.pem", folder / "ca.pem"
    )


def _common_name(cert_path: Path) -> str:
    try:
        cert = x509.load_pem_x509_certificate(cert_path.read_bytes())
    except (OSError, ValueError) as exc:
        raise KeysError(f"{cert_path}: cannot read the certificate: {exc}") from exc
    names = cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    return str(names[0].value) if names else ""


def client_identity(folder: Path) -> str:
    """The identity in an outside client's folder; :class:`KeysError` for one issued before
    clients had names of their own."""
    common_name = _common_name(Path(folder) / "cert.pem")
    if "@" not in common_name:
        raise KeysError(
            f"{folder} was issued before clients had names of their own: ask the show's "
            f"operator to issue it again (`skyquill keys SHOW --client NAME --role ROLE`)"
        )
    return common_name


def check_old_clients(keys_dir: Path) -> None:
    """:class:`KeysError` if the keys folder issued an outside operator before clients had names
    (its certificate says ``operator``, as the console's does, and no rule can shut it out).
    Old watchers and submitters need nothing: no rule admits their common names any more."""
    old = sorted(
        cert.parent.name
        for cert in (Path(keys_dir) / "clients").glob("*/cert.pem")
        if _common_name(cert) == "operator"
    )
    if old:
        raise KeysError(
            f"{keys_dir} issued outside operators before clients had names ({', '.join(old)}): "
            f"they act as the console and cannot be revoked; move the folder away and run "
            f"`skyquill keys` (or `up`) with the show file for a new CA, then issue outside "
            f"clients again (--client) and copy the new folders to companion hosts"
        )


def _now() -> datetime.datetime:
    return datetime.datetime.now(datetime.UTC)


def _write_private(path: Path, data: bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "wb") as out:
        out.write(data)
    os.chmod(path, 0o600)


def _write_public(path: Path, cert: x509.Certificate) -> None:
    path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    path.write_bytes(cert.public_bytes(serialization.Encoding.PEM))


def _key_pem(key: ec.EllipticCurvePrivateKey) -> bytes:
    return key.private_bytes(
        serialization.Encoding.PEM,
        serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption(),
    )


def _alt_names(hosts: Iterable[str]) -> list[x509.GeneralName]:
    names: list[x509.GeneralName] = []
    for host in dict.fromkeys(["localhost", "127.0.0.1", "::1", *hosts]):
        try:
            names.append(x509.IPAddress(ipaddress.ip_address(host)))
        except ValueError:
            names.append(x509.DNSName(host))
    return names


def issues_by_role(ca: x509.Certificate) -> bool:
    """Whether ``ca`` was made to give server authentication to routers only (its mark)."""
    units = ca.subject.get_attributes_for_oid(NameOID.ORGANIZATIONAL_UNIT_NAME)
    return any(unit.value == CA_PROFILE for unit in units)


def ensure_ca(keys_dir: Path, show_id: str) -> tuple[x509.Certificate, ec.EllipticCurvePrivateKey]:
    """The show CA, created when the folder has none; :class:`KeysError` for an older CA."""
    cert_path, key_path = Path(keys_dir) / "ca.pem", Path(keys_dir) / "ca.key"
    if cert_path.exists() and key_path.exists():
        try:
            cert = x509.load_pem_x509_certificate(cert_path.read_bytes())
            key = serialization.load_pem_private_key(key_path.read_bytes(), password=None)
        except (ValueError, OSError) as exc:
            raise KeysError(f"{keys_dir}: cannot read the show CA: {exc}") from exc
        if not isinstance(key, ec.EllipticCurvePrivateKey):
            raise KeysError(f"{key_path}: not an ECDSA key")
        if not issues_by_role(cert):
            raise KeysError(
                f"{keys_dir} was made by an older skyquill: any of its certificates can pose as "
                f"the router; move the folder away and run `skyquill keys` (or `up`) with the "
                f"show file for a new CA, then issue outside clients again (--client) and copy "
                f"the new folders to companion hosts"
            )
        return cert, key
    key = ec.generate_private_key(ec.SECP256R1())
    name = x509.Name(
        [
            x509.NameAttribute(NameOID.ORGANIZATION_NAME, "skyquill"),
            x509.NameAttribute(NameOID.ORGANIZATIONAL_UNIT_NAME, CA_PROFILE),
            x509.NameAttribute(NameOID.COMMON_NAME, f"skyquill show CA {show_id}"),
        ]
    )
    now = _now()
    cert = (
        x509.CertificateBuilder()
        .subject_name(name)
        .issuer_name(name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - CLOCK_SKEW)
        .not_valid_after(now + CA_LIFETIME)
        .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
        .add_extension(
            x509.KeyUsage(
                digital_signature=True,
                key_cert_sign=True,
                crl_sign=True,
                content_commitment=False,
                key_encipherment=False,
                data_encipherment=False,
                key_agreement=False,
                encipher_only=False,
                decipher_only=False,
            ),
            critical=True,
        )
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(key.public_key()), critical=False)
        .sign(key, hashes.SHA256())
    )
    _write_private(key_path, _key_pem(key))
    _write_public(cert_path, cert)
    return cert, key


def issue(
    keys_dir: Path,
    files: IdentityFiles,
    *,
    show_id: str,
    hosts: Iterable[str] = (),
    holder: str | None = None,
) -> IdentityFiles:
    """Sign a new key pair for ``files.common_name`` (replacing any there); returns ``files``.

    A router's identity gets a server certificate naming ``hosts`` (and loopback); any other
    gets a client-only certificate, and ``hosts`` is not used. ``holder`` is a person's or
    device's name kept in the subject (organisational unit), apart from the common name the
    access control matches.
    """
    ca_cert, ca_key = ensure_ca(keys_dir, show_id)
    key = ec.generate_private_key(ec.SECP256R1())
    attributes = [x509.NameAttribute(NameOID.ORGANIZATION_NAME, f"skyquill {show_id}")]
    if holder:
        attributes.append(x509.NameAttribute(NameOID.ORGANIZATIONAL_UNIT_NAME, holder))
    attributes.append(x509.NameAttribute(NameOID.COMMON_NAME, files.common_name))
    now = _now()
    router = is_router(files.common_name)
    builder = (
        x509.CertificateBuilder()
        .subject_name(x509.Name(attributes))
        .issuer_name(ca_cert.subject)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - CLOCK_SKEW)
        .not_valid_after(now + CERT_LIFETIME)
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(
            x509.ExtendedKeyUsage(_ROUTER_USAGES if router else _CLIENT_USAGES), critical=False
        )
        .add_extension(
            x509.AuthorityKeyIdentifier.from_issuer_public_key(ca_key.public_key()), critical=False
        )
    )
    if router:
        builder = builder.add_extension(
            x509.SubjectAlternativeName(_alt_names(hosts)), critical=False
        )
    cert = builder.sign(ca_key, hashes.SHA256())
    _write_private(files.key, _key_pem(key))
    _write_public(files.cert, cert)
    if files.ca != Path(keys_dir) / "ca.pem":
        _write_public(files.ca, ca_cert)
    return files


def _fits_role(cert: x509.Certificate, common_name: str, hosts: Iterable[str]) -> bool:
    """A router's certificate serves and names ``hosts``; any other is a client's, nameless."""
    try:
        usages = tuple(cert.extensions.get_extension_for_class(x509.ExtendedKeyUsage).value)
    except x509.ExtensionNotFound:
        return False
    try:
        alt = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    except x509.ExtensionNotFound:
        alt = None
    if not is_router(common_name):
        return usages == _CLIENT_USAGES and alt is None
    return usages == _ROUTER_USAGES and alt is not None and set(_alt_names(hosts)) <= set(alt)


def is_valid(files: IdentityFiles, hosts: Iterable[str] = ()) -> bool:
    """Whether the identity's files exist, match a CA that issues by role, fit the identity's
    role (a router's naming ``hosts``) and are not about to expire."""
    try:
        cert = x509.load_pem_x509_certificate(files.cert.read_bytes())
        ca = x509.load_pem_x509_certificate(files.ca.read_bytes())
        key = serialization.load_pem_private_key(files.key.read_bytes(), password=None)
    except (OSError, ValueError):
        return False
    if cert.public_key() != key.public_key() or cert.issuer != ca.subject:
        return False
    if not issues_by_role(ca):
        return False
    try:
        cert.verify_directly_issued_by(ca)
    except (InvalidSignature, ValueError, TypeError):
        return False
    common_names = cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    if not common_names or common_names[0].value != files.common_name:
        return False
    if not _fits_role(cert, files.common_name, hosts):
        return False
    return cert.not_valid_after_utc - _now() > datetime.timedelta(days=7)
