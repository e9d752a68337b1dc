"""The show's certificate authority and the certificates it issues (the ``cryptography`` package).

Layout of a show's keys folder (``show.keys_dir``; private keys 0600, folders 0700)::

    ca.pem  ca.key                  the show CA (ECDSA P-256, 5 years)
    <identity>/cert.pem  key.pem    one per service and per vehicle (common name = identity)
    clients/<name>/cert.pem key.pem ca.pem issuer.pem   outside clients (``<role>@<name>``)
    clients.json                    the outside clients admitted and revoked (trust/clients.py)
    router/trusted.pem              whom the router accepts: the show CA, admitted clients' issuers

Certificates by role: only a router's certificate may serve. It carries server and client
authentication (a companion router also joins the ground router) and the routers' host names
(from the show's endpoints), which clients verify on connecting. Every other identity's
certificate is for client authentication only, without names: rustls (Zenoh's TLS) refuses it
as a server's, so a stolen vehicle's or client's key cannot pose as the router. Every
certificate is valid for one year.

The show CA signs the show's own identities. An outside client's certificate is signed by an
issuer of its own (:func:`issue_client`): a CA made for that one certificate, whose key is
dropped once it has signed, so nothing else can ever chain to it. The router trusts the show CA
and the issuers of the clients admitted now (``trust.settings``), so revoking a client takes its
issuer out of the router's trust: its TLS handshake fails, it cannot even connect. (Zenoh's TLS
has no revocation list; this is one, kept as the router's trust anchors.)

A CA is marked (:data:`CA_PROFILE`). A keys folder whose CA lacks the mark was made by an older
skyquill, whose certificates could serve, or whose outside clients were signed by the show CA
itself and so could never be refused at connection: re-issuing its own files would leave copies
of the old ones (outside clients, companion hosts) valid, so it is refused with what to do (a
new CA) rather than used. A client holding a folder issued before clients had names of their own
(its common name was its role) is told to have it issued again (:func:`client_identity`).
"""

from __future__ import annotations

import datetime
import ipaddress
import os
import secrets
from collections.abc import Iterable
from pathlib import Path

from cryptography import x509
from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

from trust.clients import client_common_name, client_issuer_path
from trust.files import IdentityFiles, KeysError, identity_files
from trust.hosts import is_router

__all__ = [
    "CA_PROFILE",
    "IdentityFiles",
    "KeysError",
    "client_files",
    "client_identity",
    "ensure_ca",
    "identity_files",
    "is_valid",
    "issue",
    "issue_client",
]

CA_LIFETIME = datetime.timedelta(days=5 * 365)
CERT_LIFETIME = datetime.timedelta(days=365)
CLOCK_SKEW = datetime.timedelta(minutes=10)
CA_PROFILE = "certificates by role, clients by own issuers"
"""Organisational unit of a show CA that gives server authentication to routers only and signs
no outside client (each has an issuer of its own)."""
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
    """Whether ``ca`` was made to give server authentication to routers only and to sign no
    outside client (its mark)."""
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
                f"{keys_dir} was made by an older skyquill: its certificates could pose as the "
                f"router or its outside clients could not be shut out; move the folder away "
                f"and run `skyquill keys` (or `up`) with the "
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
    cert = _self_signed_ca(name, key, CA_LIFETIME)
    _write_private(key_path, _key_pem(key))
    _write_public(cert_path, cert)
    return cert, key


def _self_signed_ca(
    name: x509.Name, key: ec.EllipticCurvePrivateKey, lifetime: datetime.timedelta
) -> x509.Certificate:
    """A CA certificate that signs end certificates only (no CA below it)."""
    now = _now()
    return (
        x509.CertificateBuilder()
        .subject_name(name)
        .issuer_name(name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - CLOCK_SKEW)
        .not_valid_after(now + lifetime)
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


def issue(
    keys_dir: Path,
    files: IdentityFiles,
    *,
    show_id: str,
    hosts: Iterable[str] = (),
) -> IdentityFiles:
    """Sign a new key pair for the show's own identity ``files.common_name`` with the show CA
    (replacing any there); returns ``files``.

    A router's identity gets a server certificate naming ``hosts`` (and loopback); any other
    gets a client-only certificate, and ``hosts`` is not used.
    """
    ca_cert, ca_key = ensure_ca(keys_dir, show_id)
    _sign(files, ca_cert, ca_key, show_id=show_id, hosts=hosts)
    if files.ca != Path(keys_dir) / "ca.pem":
        _write_public(files.ca, ca_cert)
    return files


def issue_client(keys_dir: Path, name: str, role: str, *, show_id: str) -> IdentityFiles:
    """Sign a new key pair for the outside client ``name`` by an issuer of its own, made for
    this one certificate and then forgotten (its key is never written); returns its files.

    The folder gets the certificate, its key, the show CA (to verify the router) and the issuer
    (``issuer.pem``, public: the router trusts it while the client is admitted).
    """
    ca_cert, _ = ensure_ca(keys_dir, show_id)
    files = client_files(keys_dir, name, role)
    issuer_key = ec.generate_private_key(ec.SECP256R1())
    issuer_name = x509.Name(
        [
            x509.NameAttribute(NameOID.ORGANIZATION_NAME, f"skyquill {show_id}"),
            x509.NameAttribute(NameOID.SERIAL_NUMBER, secrets.token_hex(16)),  # one of its kind
            x509.NameAttribute(NameOID.COMMON_NAME, f"issuer of {files.common_name}"),
        ]
    )
    issuer = _self_signed_ca(issuer_name, issuer_key, CERT_LIFETIME)
    _sign(files, issuer, issuer_key, show_id=show_id, holder=name)
    _write_public(files.ca, ca_cert)
    _write_public(client_issuer_path(keys_dir, name), issuer)
    return files


def _sign(
    files: IdentityFiles,
    issuer: x509.Certificate,
    issuer_key: ec.EllipticCurvePrivateKey,
    *,
    show_id: str,
    hosts: Iterable[str] = (),
    holder: str | None = None,
) -> None:
    """Write a new key and its certificate for ``files.common_name``, signed by ``issuer``.
    ``holder`` is a person's or device's name kept in the subject (organisational unit), apart
    from the common name the access control matches."""
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
        .issuer_name(issuer.subject)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - CLOCK_SKEW)
        .not_valid_after(now + CERT_LIFETIME)
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .add_extension(
            x509.ExtendedKeyUsage(_ROUTER_USAGES if router else _CLIENT_USAGES), critical=False
        )
        .add_extension(
            x509.AuthorityKeyIdentifier.from_issuer_public_key(issuer_key.public_key()),
            critical=False,
        )
    )
    if router:
        builder = builder.add_extension(
            x509.SubjectAlternativeName(_alt_names(hosts)), critical=False
        )
    cert = builder.sign(issuer_key, hashes.SHA256())
    _write_private(files.key, _key_pem(key))
    _write_public(files.cert, cert)


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
