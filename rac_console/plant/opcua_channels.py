"""The OPC UA server's channels held to its security policy (the server's process only).

asyncua keeps a channel's first policy (None) when the client asks for it, whatever the
server offers, and checks a session's certificate only when the client sends one: left
alone, a client with no certificate would read and write in the clear.
"""

from __future__ import annotations

from typing import Any

from asyncua import ua

from ..commands.opcua import OpcUaSettings
from .opcua_security import POLICY_URI, mode_of

#: What a client may ask on a channel whatever its security: how to reach the server.
_DISCOVERY = (
    ua.ObjectIds.GetEndpointsRequest_Encoding_DefaultBinary,
    ua.ObjectIds.FindServersRequest_Encoding_DefaultBinary,
)


def guard_channels(settings: OpcUaSettings, trusted: Any) -> None:
    """With a security policy, nothing but discovery on a channel without it, and a
    session only for the certificate the channel was opened with, trusted. The
    server's process serves nothing else: its asyncua is changed here, for it alone."""
    from asyncua.crypto.uacrypto import x509_from_der
    from asyncua.server.uaprocessor import UaProcessor
    from asyncua.ua.ua_binary import struct_from_binary

    mode = mode_of(settings.security)
    process = UaProcessor._process_message

    async def guarded(self: Any, typeid: Any, header: Any, sequence: Any, body: Any) -> Any:
        if typeid.Identifier not in _DISCOVERY:
            policy = self._connection.security_policy
            if policy.URI != POLICY_URI or policy.Mode != mode or not policy.peer_certificate:
                raise ua.UaStatusCodeError(ua.StatusCodes.BadSecurityPolicyRejected)
            create = ua.ObjectIds.CreateSessionRequest_Encoding_DefaultBinary
            if typeid.Identifier == create:
                params = struct_from_binary(ua.CreateSessionParameters, body.copy())
                if params.ClientCertificate not in (None, b"", policy.peer_certificate):
                    raise ua.UaStatusCodeError(ua.StatusCodes.BadCertificateInvalid)
                await trusted(x509_from_der(policy.peer_certificate), params.ClientDescription)
        return await process(self, typeid, header, sequence, body)

    UaProcessor._process_message = guarded
