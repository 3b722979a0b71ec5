"""The library's exceptions, each saying what the console says, and what each means for
the controller: whether anything was sent, and whether a write may have happened.

:class:`RacError` is the package's own base (every error rac_console raises), so
``except rac.RacError`` catches all of them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..protocol.errors import RacError as RacError  # the package's base, named here too
from ..protocol.hresult import hresult_name

if TYPE_CHECKING:
    from .results import Written


class Refused(RacError):
    """Nothing was sent: read-only, a profile's rules (``allow``, a ``confirm`` profile
    with no answer), a value or a line that cannot be written, a closed connection, a
    broken config file. The message says why, and how to write it, as the console does."""


class UnknownTarget(RacError, KeyError):
    """A cell holds no target of that name (``cell["robotC"]``): nothing was sent. Also
    a ``KeyError``, as a mapping's missing key is; its message names the cell's targets."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""  # a KeyError would quote it


class ControllerError(RacError):
    """The controller answered an error HRESULT: ``code`` (an int) and ``name``
    (``E_INVALIDARG``; None for a code outside RAC's table, such as a user-defined
    error). Any code but S_OK is one, as in the console: RAC names no other success, so
    a code with COM's success bit (S_FALSE, 1) is one too, and its message says so. For
    a write, ``written`` holds what the read-back found."""

    def __init__(self, message: str, code: int, written: Written | None = None) -> None:
        super().__init__(message)
        self.code = code
        self.name = hresult_name(code)
        self.written = written


class OutcomeUnknown(RacError):
    """A write went out and no answer came (a timeout, the connection cut): it may have
    been applied or may still arrive. It is never sent again; ``written`` holds the value
    before and, when the read after it answered, what the controller held then."""

    def __init__(self, message: str, written: Written | None = None) -> None:
        super().__init__(message)
        self.written = written


class ReadBackMismatch(RacError):
    """The controller answered S_OK, but the read-back does not show the value written:
    it holds another value (``written.verified`` False), or the read-back failed
    (``written.read_back`` None). The CLI exits 1 for it; a script should not go on as
    if the write were done."""

    def __init__(self, message: str, written: Written) -> None:
        super().__init__(message)
        self.written = written


class UnreadableReply(RacError):
    """The controller's reply to a read could not be read (not RAC, or not an answer to
    that request): nothing was written. The message quotes the reply, escaped; ``raw``
    is it as it came (None when it was too long to keep). A write that got such a reply
    is :class:`OutcomeUnknown`."""

    def __init__(self, message: str, raw: bytes | None = None) -> None:
        super().__init__(message)
        self.raw = raw


class ConnectionFailed(RacError, ConnectionError):
    """No connection could be opened, or it ended before a read's answer: nothing was
    written. ``hint`` is what ``rac-console check``
    says to check for such a failure; ``problem`` names it in a word (``refused``,
    ``timed out``, ...; None when the connection ended after it was opened)."""

    def __init__(
        self,
        message: str,
        *,
        problem: str | None = None,
        hint: str | None = None,
    ) -> None:
        super().__init__(message)
        self.problem = problem
        self.hint = hint


class Timeout(RacError, TimeoutError):
    """A read got no answer within the timeout: nothing was written (a write that got no
    answer is :class:`OutcomeUnknown`)."""
