"""Who may talk to the OPC UA server, and how.

On loopback with no security policy, anyone on this machine may read (a tag browser,
Ignition on the same PC). Anywhere else, Basic256Sha256: the server's certificate is
made on first use in the user's folder (its path said), and a client is let in only
when its certificate is in the ``trusted`` folder beside it; a certificate refused is
kept in ``rejected`` and the user told where to move it. With ``--opcua-user`` the
client must also give that user's password.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import platform
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from asyncua import Server, ua
from asyncua.common.utils import ServiceError
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.crypto.permission_rules import User, UserRole
from asyncua.crypto.truststore import TrustStore
from asyncua.crypto.validator import CertificateValidator, CertificateValidatorOptions
from cryptography import x509
from cryptography.hazmat.primitives.serialization import Encoding
from cryptography.x509.oid import ExtendedKeyUsageOID

from ..commands.opcua import OpcUaSettings, Security

#: Where the server's certificate and the trusted clients' live (else the user's data
#: folder): tests, and a service that keeps its state elsewhere.
FOLDER_ENV = "RAC_CONSOLE_OPCUA_DIR"

_POLICIES = {
    Security.SIGN: ua.SecurityPolicyType.Basic256Sha256_Sign,
    Security.ENCRYPT: ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt,
}
POLICY_URI = "http://opcfoundation.org/UA/SecurityPolicy#Basic256Sha256"


def mode_of(security: Security) -> ua.MessageSecurityMode:
    """The message security mode a channel must have."""
    if security is Security.SIGN:
        return ua.MessageSecurityMode.Sign
    return ua.MessageSecurityMode.SignAndEncrypt


def opcua_folder() -> Path:
    """The folder of the server's certificate, key and trusted clients."""
    given = os.environ.get(FOLDER_ENV)
    if given:
        return Path(given).expanduser()
    from platformdirs import user_data_path

    return user_data_path("rac-console", appauthor=False) / "opcua"


def application_uri() -> str:
    return f"urn:rac-console:server:{platform.node() or 'localhost'}"


class PasswordUsers:
    """Anyone (no ``--opcua-user``), or the one user with its password. Nobody is an
    administrator: a client writes only what ``--opcua-writes`` lets through."""

    def __init__(self, username: str | None, password: str | None) -> None:
        self._username = username
        self._password = password or ""

    def get_user(
        self,
        iserver: Any,
        username: str | None = None,
        password: str | None = None,
        certificate: Any = None,
    ) -> User | None:
        if self._username is None:
            return User(role=UserRole.User)
        given_user = (username or "").encode()
        given_password = (password or "").encode()
        same_user = hmac.compare_digest(given_user, self._username.encode())
        same_password = hmac.compare_digest(given_password, self._password.encode())
        return (
            User(role=UserRole.User, name=self._username) if same_user and same_password else None
        )


class TrustedFolder:
    """Lets in the clients whose certificate is in ``trusted`` (read again at each
    session: a certificate copied in is taken without a restart)."""

    def __init__(self, folder: Path, say: Callable[[str], None]) -> None:
        self.trusted = folder / "trusted"
        self.rejected = folder / "rejected"
        self._say = say
        self._said: dict[bytes, float] = {}  # a certificate refused: when it was said

    async def __call__(self, cert: x509.Certificate, app: ua.ApplicationDescription) -> None:
        options = (
            CertificateValidatorOptions.TIME_RANGE
            | CertificateValidatorOptions.URI
            | CertificateValidatorOptions.TRUSTED
            | CertificateValidatorOptions.PEER_CLIENT
        )
        store = TrustStore([self.trusted], [])
        try:
            if not any(path.is_file() for path in self.trusted.iterdir()):
                raise ServiceError(ua.StatusCodes.BadCertificateUntrusted)
            await store.load()  # a folder of no certificate: ValueError
            await CertificateValidator(options, store).validate(cert, app)
        except (ServiceError, ValueError, OSError):
            self._refused(cert)
            raise ServiceError(ua.StatusCodes.BadCertificateUntrusted) from None

    def _refused(self, cert: x509.Certificate) -> None:
        """Kept in ``rejected`` (a hundred at most: anyone who reaches the port can try)
        and said, each certificate once a minute at most."""
        der = cert.public_bytes(Encoding.DER)
        now = time.monotonic()
        if now - self._said.get(der, -60.0) < 60 or len(self._said) > 1000:
            return
        self._said[der] = now
        self.rejected.mkdir(parents=True, exist_ok=True)
        name = cert.subject.rfc4514_string() or "client"
        safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in name)[:60]
        path = self.rejected / f"{safe}-{hashlib.sha256(der).hexdigest()[:12]}.der"
        if not path.exists() and sum(1 for _ in self.rejected.iterdir()) >= 100:
            self._say(f"an OPC UA client's certificate was refused ({self.rejected} is full)")
            return
        path.write_bytes(der)
        self._say(
            "an OPC UA client's certificate was refused (not trusted, or not valid now): "
            f"to let it in, move {path} into {self.trusted}"
        )


async def secure(
    server: Server, settings: OpcUaSettings, say: Callable[[str], None]
) -> tuple[Path, bool] | None:
    """Set the server's policies, identities and certificate; the certificate's path
    when one is used, and whether it was made now."""
    tokens: list[type] = [
        ua.UserNameIdentityToken if settings.username else ua.AnonymousIdentityToken
    ]
    server.set_identity_tokens(tokens)
    if settings.security is Security.NONE:
        server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        return None
    folder = opcua_folder()
    folder.mkdir(parents=True, exist_ok=True)
    if os.name != "nt":
        folder.chmod(0o700)
    (folder / "trusted").mkdir(exist_ok=True)
    key, cert = folder / "server-key.pem", folder / "server-cert.der"
    before = cert.read_bytes() if cert.is_file() else None  # remade when it expires
    await setup_self_signed_certificate(
        key,
        cert,
        application_uri(),
        platform.node() or "localhost",
        [ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH],
        {"commonName": "rac-console", "organizationName": "rac-console"},
    )
    if os.name != "nt":
        key.chmod(0o600)
    await server.load_certificate(str(cert))
    await server.load_private_key(str(key))
    server.set_security_policy([_POLICIES[settings.security]])
    made = before != cert.read_bytes()
    server.set_certificate_validator(TrustedFolder(folder, say))
    return cert, made
