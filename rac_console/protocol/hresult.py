"""HRESULT codes: names, descriptions and ranges (spec section 4)."""

from __future__ import annotations

from typing import NamedTuple


class HResultInfo(NamedTuple):
    code: int
    name: str
    description: str


S_OK = 0x00000000
E_NOTIMPL = 0x80004001
E_ABORT = 0x80004004
E_FAIL = 0x80004005
E_UNEXPECTED = 0x8000FFFF
E_INVALIDRCVPACKET = 0x80010001
E_INVALIDSNDPACKET = 0x80010002
E_INVALIDARGTYPE = 0x80010003
E_ROBOTISBUSY = 0x80010004
E_INVALIDCOMMAND = 0x80010005
E_PACKETSIZEOVER = 0x80010011
E_ARGSIZEOVER = 0x80010012
E_ACCESSDENIED = 0x80070005
E_HANDLE = 0x80070006
E_OUTOFMEMORY = 0x8007000E
E_INVALIDARG = 0x80070057

HRESULTS: dict[int, HResultInfo] = {
    info.code: info
    for info in (
        HResultInfo(S_OK, "S_OK", "success"),
        HResultInfo(E_NOTIMPL, "E_NOTIMPL", "not implemented"),
        HResultInfo(E_ABORT, "E_ABORT", "aborted"),
        HResultInfo(E_FAIL, "E_FAIL", "failed"),
        HResultInfo(E_UNEXPECTED, "E_UNEXPECTED", "fatal error"),
        HResultInfo(
            E_INVALIDRCVPACKET,
            "E_INVALIDRCVPACKET",
            "the controller received an invalid packet and closes the connection",
        ),
        HResultInfo(E_INVALIDSNDPACKET, "E_INVALIDSNDPACKET", "invalid send packet"),
        HResultInfo(E_INVALIDARGTYPE, "E_INVALIDARGTYPE", "invalid argument type"),
        HResultInfo(
            E_ROBOTISBUSY, "E_ROBOTISBUSY", "robot busy: a motion command arrived while moving"
        ),
        HResultInfo(E_INVALIDCOMMAND, "E_INVALIDCOMMAND", "invalid command string; not executed"),
        HResultInfo(E_PACKETSIZEOVER, "E_PACKETSIZEOVER", "received packet too large"),
        HResultInfo(E_ARGSIZEOVER, "E_ARGSIZEOVER", "received argument too large"),
        HResultInfo(E_ACCESSDENIED, "E_ACCESSDENIED", "access denied"),
        HResultInfo(E_HANDLE, "E_HANDLE", "invalid handle"),
        HResultInfo(E_OUTOFMEMORY, "E_OUTOFMEMORY", "out of memory"),
        HResultInfo(E_INVALIDARG, "E_INVALIDARG", "invalid argument"),
    )
}

USER_RANGE = range(0x80040200, 0x80050000)


def hresult_name(code: int) -> str | None:
    """The symbolic name, or None for a code outside the table."""
    info = HRESULTS.get(code)
    return info.name if info else None


def succeeded(code: int) -> bool:
    """SUCCEEDED(): the severity bit is clear."""
    return not code & 0x80000000


#: Said of a code with COM's success bit but not S_OK (S_FALSE is 1): RAC's table names
#: S_OK alone as success, so every front end takes such an answer as a failure.
NOT_S_OK = "not S_OK, the one success RAC defines (taken as a failure)"


def describe_hresult(code: int) -> str:
    """One line for people: ``E_INVALIDARG 0x80070057: invalid argument``."""
    info = HRESULTS.get(code)
    if info:
        return f"{info.name} 0x{code:08X}: {info.description}"
    if code in USER_RANGE:
        return f"0x{code:08X}: user-defined error"
    return f"0x{code:08X}: {NOT_S_OK if succeeded(code) else 'unknown error'}"
