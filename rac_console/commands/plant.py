"""Feeding the plant, as typed: a broker's address, the metrics endpoint, ``publish``.

Pure: text in, addresses out, every refusal an InputError of one line saying how to
write it. A password never reaches a message, a history file or a topic: an address
with one in it is refused without being repeated.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..protocol import InputError
from ..protocol.text import endpoint, terminal_safe

MQTT_PORT = 1883
MQTTS_PORT = 8883
METRICS_PORT = 9108
#: Where user, password and CA file come from (the config's [mqtt] table, else these).
USERNAME_ENV = "RAC_MQTT_USERNAME"
PASSWORD_ENV = "RAC_MQTT_PASSWORD"
CA_FILE_ENV = "RAC_MQTT_CA_FILE"
MQTT_USAGE = "mqtt://HOST[:PORT]/PREFIX (or mqtts:// for TLS), e.g. mqtt://broker.plant/line2"
#: Characters a topic level may not hold: MQTT's wildcards, its separator and NUL.
_TOPIC_FORBIDDEN = frozenset("+#/\0")


@dataclass(frozen=True)
class MqttAddress:
    """A broker and the prefix of every topic published to it."""

    host: str
    port: int
    prefix: str  # "line2" or "plant/line2": no leading or trailing /
    tls: bool = False

    def __str__(self) -> str:
        return f"{'mqtts' if self.tls else 'mqtt'}://{endpoint(self.host, self.port)}/{self.prefix}"


#: Seconds between pings to a quiet broker (``keepalive`` in ``[mqtt]``): a broker that
#: does not answer one within as long again is dropped and tried again.
KEEPALIVE = 15
KEEPALIVE_RANGE = (2, 3600)


@dataclass(frozen=True)
class Credentials:
    """What the broker is told who we are, whom to trust and how often to ping: the
    config's ``[mqtt]`` table. Never printed."""

    username: str | None = None
    password: str | None = None
    ca_file: str | None = None
    keepalive: int = KEEPALIVE

    def __repr__(self) -> str:  # a traceback or a debug print shows no password
        password = "<set>" if self.password else "<none>"
        return f"Credentials(username={self.username!r}, password={password})"


NO_CREDENTIALS = Credentials()


def parse_mqtt_address(text: str) -> MqttAddress:
    """``mqtt://HOST[:PORT]/PREFIX`` or ``mqtts://…``; InputError saying how to write it."""
    text = text.strip()
    scheme, _, rest = text.partition("://")
    if not rest:
        raise InputError(f"give the broker as {MQTT_USAGE}")
    if scheme.lower() not in ("mqtt", "mqtts"):
        raise InputError(f"the broker's address starts with mqtt:// or mqtts://: {MQTT_USAGE}")
    if "@" in rest:  # anywhere: a password may hold / ? # (base64 holds /); not repeated
        raise InputError(
            "no user or password in the broker's address (it would show in history and "
            f"process lists), and no @ in a topic prefix: put them in the config file's "
            f"[mqtt] table or in {USERNAME_ENV} and {PASSWORD_ENV}"
        )
    authority = rest.split("/", 1)[0]
    if "?" in rest or "#" in authority:  # urlsplit would drop what follows, silently
        raise InputError(f"the broker's address takes no ? or # part: {MQTT_USAGE}")
    from urllib.parse import urlsplit

    try:
        parts = urlsplit(text)
        port = parts.port
    except ValueError:
        raise InputError(f"the broker's port is a number from 1 to 65535: {MQTT_USAGE}") from None
    host = parts.hostname or ""
    if not host or not host.isprintable() or any(c.isspace() for c in host):
        raise InputError(f"the broker's address names no host: {MQTT_USAGE}")
    if not _host_name_ok(host):
        raise InputError(
            f"the broker's host {terminal_safe(host)!s} is not a name or address a resolver "
            "takes (labels of 1 to 63 letters, digits and -, 253 characters in all)"
        )
    path = rest[len(authority) :]  # as typed: urlsplit would take a # for a fragment
    tls = scheme.lower() == "mqtts"
    if port == 0:
        raise InputError(f"the broker's port is a number from 1 to 65535: {MQTT_USAGE}")
    prefix = path[1:].rstrip("/")
    if len(prefix.encode("utf-8")) > MAX_PREFIX:
        raise InputError(f"the topic prefix is longer than {MAX_PREFIX} bytes: {MQTT_USAGE}")
    if prefix.startswith("$"):
        raise InputError("a topic prefix starting with $ is the broker's own ($SYS): use line2")
    if not prefix:
        raise InputError(
            f"give a topic prefix after the broker, as in {'mqtts' if tls else 'mqtt'}://"
            f"{terminal_safe(authority)}/line2: values go to PREFIX/<target>/<variable>"
        )
    for level in prefix.split("/"):
        topic_level(level, "the topic prefix")
    return MqttAddress(host, port or (MQTTS_PORT if tls else MQTT_PORT), prefix, tls)


#: Bytes of a topic prefix, at most: MQTT's topics hold 65,535, and the target and the
#: variable follow it.
MAX_PREFIX = 1000


def _host_name_ok(host: str) -> bool:
    """Whether the resolver takes ``host`` (an IP address, or a name IDNA encodes)."""
    import ipaddress

    try:
        ipaddress.ip_address(host)
        return True
    except ValueError:
        pass
    try:
        encoded = host.encode("idna")
    except UnicodeError:
        return False
    return len(encoded) <= 253


def topic_level(name: str, what: str) -> str:
    """``name`` as one level of a topic; InputError when it cannot be one (empty, or
    holding +, #, / or NUL, which would change what the topic means)."""
    if not name:
        raise InputError(f"{what} has an empty level (two / in a row): write line2 or plant/line2")
    bad = sorted(_TOPIC_FORBIDDEN.intersection(name))
    if bad or not name.isprintable():
        shown = " ".join(repr(c) for c in bad) or "control characters"
        raise InputError(
            f"{what} '{terminal_safe(name)}' holds {shown}, which MQTT topics reserve: "
            "use letters, digits, - _ . and :"
        )
    return name


@dataclass(frozen=True)
class MetricsAddress:
    """Where ``/metrics`` is served."""

    host: str
    port: int

    @property
    def loopback(self) -> bool:
        import ipaddress

        try:
            return ipaddress.ip_address(self.host).is_loopback
        except ValueError:
            return self.host == "localhost"

    def __str__(self) -> str:
        return endpoint(self.host, self.port)


METRICS_USAGE = (
    "[HOST:]PORT, e.g. --metrics 9108 (this machine only) or 127.0.0.1:9108 (port 0: any free one)"
)


def parse_metrics_address(text: str) -> MetricsAddress:
    """``9108`` (loopback), ``127.0.0.1:9108`` or ``[::1]:9108``. Any address but
    loopback must be written out: it opens the values to the network."""
    text = text.strip()
    host, port_text = "127.0.0.1", text
    if text.startswith("["):
        host, _, port_text = text[1:].partition("]:")
    elif ":" in text:
        host, _, port_text = text.rpartition(":")
    if not (port_text.isascii() and port_text.isdigit()) or not 0 <= int(port_text) < 65536:
        raise InputError(f"--metrics takes {METRICS_USAGE}, got {terminal_safe(text)!r}")
    if not host or not host.isprintable() or any(c.isspace() for c in host):
        raise InputError(f"--metrics takes {METRICS_USAGE}, got {terminal_safe(text)!r}")
    return MetricsAddress(host, int(port_text))


def publish_setting(where: str, value: object, fail: Callable[[str], InputError]) -> str | None:
    """A profile's or a cell's ``publish = "mqtt://HOST/PREFIX"`` in the config file,
    checked (``fail`` makes the error, naming the file)."""
    if value is None:
        return None
    if not isinstance(value, str):
        raise fail(f'{where} publish: write publish = "mqtt://broker/line2" (text in quotes)')
    try:
        return str(parse_mqtt_address(value))
    except InputError as exc:
        raise fail(f"{where} publish: {exc}") from None


# ------------------------------------------------------------------ publish


@dataclass(frozen=True)
class Publish:
    """``publish mqtt://HOST/PREFIX``, ``publish off``, or ``publish`` (where to)."""

    address: MqttAddress | None
    off: bool = False


PUBLISH_USAGE = f"publish {MQTT_USAGE}; publish off stops; publish alone says where"


def parse_publish(text: str) -> Publish:
    words = text.split()
    if not words:
        return Publish(None)
    if len(words) > 1:
        raise InputError(f"publish takes one address: {PUBLISH_USAGE}")
    if words[0].lower() == "off":
        return Publish(None, off=True)
    return Publish(parse_mqtt_address(words[0]))
