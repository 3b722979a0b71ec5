"""A script's connection through the agent (``rac.connect``): its requests, one at a
time, on the agent's one connection to the controller.

The library keeps its own write gate (the script's ``confirm`` is asked in the script,
its refusals say what a script passes, a put's ``verify`` is the call's), and hands
each request the gate let out to :class:`AgentSession`, which the agent runs on the
shared connection in its turn (a write after every write received before it) under the
agent's rules for the target: a write the agent's read-only or a profile's ``allow``
refuses is never sent (:func:`agent_refusal`).

If the agent goes away, the request on the way is failed (a write's outcome unknown,
never sent again), a warning is logged once, and the next request goes over a session
of the connection's own.
"""

from __future__ import annotations

import contextlib
import logging
import threading
from collections.abc import Callable

from ..commands.target import Target
from ..protocol.request import Request
from ..session import Session
from ..session.types import Disconnected, NotSent, Reply, State, TransportError
from . import endpoint as endpoints
from .hellos import greet_agent
from .wire import Channel, ChannelClosed

LOG = logging.getLogger("rac_console")

#: Logged once when the agent went away and the connection goes on by itself.
GONE = "the agent stopped: rac.connect to {address} goes on with a session of its own"
#: A request on its way when the agent went away.
CUT = "the agent stopped while this request was on its way: its outcome is unknown"


def attach_requests(target: Target, timeout: float, client: str = "script") -> AgentSession | None:
    """A session through the running agent that holds ``target``; None when there is
    no agent, it does not hold that target, or it turns this release away."""
    if not endpoints.present():
        return None
    greeted = greet_agent(target, client, want="requests", timeout=timeout)
    if greeted is None:
        return None
    channel, answer = greeted
    if answer.get("op") != "welcome":  # not held, or another release: direct
        channel.close()
        return None
    assert target.host is not None
    return AgentSession(
        channel, str(answer.get("client", client)), target.host, target.port, timeout
    )


class AgentSession(Session):
    """A :class:`~rac_console.session.Session` whose requests the agent sends."""

    def __init__(self, channel: Channel, name: str, host: str, port: int, timeout: float) -> None:
        super().__init__(host, port, timeout=timeout)
        self.name = name
        self._channel: Channel | None = channel
        self._own: Session | None = None  # once the agent went away
        self._lock = threading.Lock()

    @property
    def via_agent(self) -> bool:
        return self._channel is not None

    @property
    def state(self) -> State:
        own = self._own
        return own.state if own is not None else "connected"

    def connect(self) -> None:
        """The agent's connection is its own to open; once it is gone, ours."""
        if self._own is not None:
            self._own.connect()

    def exchange(
        self,
        request: Request,
        *,
        poll: bool = False,
        cancelled: Callable[[], bool] | None = None,
        observe: bool = True,
    ) -> Reply:
        with self._lock:
            channel = self._channel
            if channel is None:
                return self._alone().exchange(request, poll=poll, cancelled=cancelled)
            if cancelled is not None and cancelled():
                raise NotSent("cancelled before it was sent")
            try:
                channel.send({"op": "request", "request": request})
                answer = channel.receive()
            except (ChannelClosed, OSError):
                self._gone()
                if request.read_only_safe:  # a read is asked again, by ourselves
                    return self._alone().exchange(request, poll=poll, cancelled=cancelled)
                raise Disconnected(CUT) from None
        if answer.get("op") == "reply":
            reply = answer["reply"]
            if not isinstance(reply, Reply):
                raise Disconnected(CUT)
            self.last_rtt = reply.rtt
            return reply
        error = answer.get("error")
        if answer.get("op") == "failed" and isinstance(error, TransportError):
            raise error
        raise Disconnected(CUT)

    def _gone(self) -> None:
        """The agent went away: said once; the next request goes by ourselves."""
        if self._channel is not None:
            self._channel.close()
            self._channel = None
            LOG.warning(GONE.format(address=self.address))

    def _alone(self) -> Session:
        if self._own is None:
            self._own = Session(self.host, self.port, timeout=self.timeout)
        return self._own

    def close(self) -> None:
        with self._lock:
            channel, self._channel = self._channel, None
            if channel is not None:
                with contextlib.suppress(ChannelClosed):
                    channel.send({"op": "bye"})
                channel.close()
            if self._own is not None:
                self._own.close()
