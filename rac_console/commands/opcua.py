"""Serving the watched values over OPC UA, as typed: the endpoint, its security.

Pure: text in, settings out, every refusal an InputError of one line saying how to
write it. An endpoint on the network without a security policy is refused here, before
anything listens: SCADA's clients would otherwise read (and, with writes on, write) the
cell's values in the clear, with no way to know who they talk to.
"""

from __future__ import annotations

import enum
import ipaddress
from dataclasses import dataclass

from ..protocol import InputError
from ..protocol.text import endpoint, terminal_safe

OPCUA_PORT = 4840
OPCUA_USAGE = "opc.tcp://HOST:PORT, e.g. opc.tcp://127.0.0.1:4840"
#: The password of ``--opcua-user`` (never on the command line: ps shows it).
PASSWORD_ENV = "RAC_OPCUA_PASSWORD"
#: Our namespace: every node of the watched values is in it.
NAMESPACE_URI = "urn:rac-console:watched"


class Security(enum.Enum):
    """``--opcua-security``: none (loopback only), or Basic256Sha256 signing, or signing
    and encrypting."""

    NONE = "none"
    SIGN = "sign"
    ENCRYPT = "encrypt"


@dataclass(frozen=True)
class OpcUaAddress:
    """Where the server listens."""

    host: str
    port: int

    @property
    def loopback(self) -> bool:
        """Only this machine can reach it (127.0.0.0/8, ::1, localhost)."""
        if self.host == "localhost":
            return True
        try:
            return ipaddress.ip_address(self.host).is_loopback
        except ValueError:
            return False

    def __str__(self) -> str:
        return f"opc.tcp://{endpoint(self.host, self.port)}"


@dataclass(frozen=True)
class OpcUaSettings:
    """``--opcua`` and the options that go with it."""

    address: OpcUaAddress
    security: Security = Security.NONE
    writes: bool = False  # --opcua-writes: a client's write goes through the write gate
    username: str | None = None
    password: str | None = None

    def __repr__(self) -> str:  # a traceback or a debug print shows no password
        password = "<set>" if self.password else "<none>"
        return f"OpcUaSettings({self.address}, {self.security.value}, password={password})"


def parse_opcua_address(text: str) -> OpcUaAddress:
    """``opc.tcp://127.0.0.1:4840`` (the port may be left out: 4840; 0 takes a free one)."""
    text = text.strip()
    shown = terminal_safe(text)
    scheme, sep, rest = text.partition("://")
    if not sep or scheme.lower() != "opc.tcp":
        raise InputError(f"--opcua takes {OPCUA_USAGE}, got {shown!r}")
    rest = rest.rstrip("/")
    if "/" in rest or "@" in rest:
        raise InputError(f"--opcua takes {OPCUA_USAGE} (no path, no user), got {shown!r}")
    host, port_text = rest, str(OPCUA_PORT)
    if rest.startswith("["):
        host, _, tail = rest[1:].partition("]")
        if tail:
            port_text = tail.removeprefix(":")
    elif ":" in rest:
        host, _, port_text = rest.rpartition(":")
    if not (port_text.isascii() and port_text.isdigit()) or not 0 <= int(port_text) < 65536:
        raise InputError(f"--opcua takes {OPCUA_USAGE}: the port is 0-65535, got {shown!r}")
    if not host or not host.isprintable() or any(c.isspace() for c in host):
        raise InputError(f"--opcua takes {OPCUA_USAGE}, got {shown!r}")
    return OpcUaAddress(host, int(port_text))


def opcua_settings(
    endpoint_text: str,
    security: str | None,
    writes: bool,
    username: str | None,
    password: str | None,
) -> OpcUaSettings:
    """The settings of ``--opcua``, checked: an address other than loopback needs
    ``--opcua-security sign`` or ``encrypt``; a user needs a password."""
    address = parse_opcua_address(endpoint_text)
    chosen = Security(security) if security is not None else Security.NONE
    if chosen is Security.NONE and not address.loopback:
        raise InputError(
            f"--opcua {address}: {terminal_safe(address.host)} is not a loopback address and "
            "needs a security policy: add --opcua-security encrypt (or sign), or serve on "
            "opc.tcp://127.0.0.1"
        )
    if username is not None and not password:
        raise InputError(
            f"--opcua-user {terminal_safe(username)} needs its password in {PASSWORD_ENV} "
            "(never on the command line)"
        )
    if username is not None and chosen is Security.NONE:
        raise InputError(
            "--opcua-user would send the password unencrypted: add --opcua-security encrypt"
        )
    return OpcUaSettings(address, chosen, writes, username, password if username else None)
