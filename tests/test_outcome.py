"""The outcome of an answered exchange, filled in one step on the hot path, is the same
object as one built field by field: equal, frozen, with every field."""

from __future__ import annotations

import dataclasses

import pytest

from rac_console.commands.language import Get, VarRef
from rac_console.commands.outcome import ExitStatus, Outcome
from rac_console.engine.exchange.execute import execute
from rac_console.protocol import kind_of
from rac_console.session import Session
from rac_console.sim.thread import SimulatorThread


def test_an_answered_outcome_is_the_outcome_built_field_by_field() -> None:
    with SimulatorThread() as sim:
        session = Session(sim.host, sim.port, timeout=2.0)
        try:
            outcome = execute(session, Get(VarRef(kind_of("I"), 3)), line="get I 3")
        finally:
            session.close()
    assert all(hasattr(outcome, f.name) for f in dataclasses.fields(Outcome))
    built = Outcome(
        outcome.request,
        outcome.status,
        outcome.var,
        outcome.response_text,
        outcome.response,
        outcome.rtt,
        outcome.error,
        outcome.input_line,
        outcome.written,
    )
    assert outcome == built and outcome.to_json() == built.to_json()
    assert outcome.ok and outcome.status is ExitStatus.OK and outcome.input_line == "get I 3"
    with pytest.raises(dataclasses.FrozenInstanceError):
        outcome.error = "changed"  # type: ignore[misc]
    assert dataclasses.replace(outcome, error="x").error == "x"


def test_an_outcome_with_a_controller_error_is_the_outcome_built_field_by_field() -> None:
    with SimulatorThread() as sim:
        session = Session(sim.host, sim.port, timeout=2.0)
        try:
            outcome = execute(session, Get(VarRef(kind_of("I"), 99999)))
        finally:
            session.close()
    assert outcome.status is ExitStatus.CONTROLLER_ERROR and outcome.error
    built = Outcome(
        outcome.request,
        outcome.status,
        outcome.var,
        outcome.response_text,
        outcome.response,
        outcome.rtt,
        outcome.error,
    )
    fields = {f.name: getattr(outcome, f.name) for f in dataclasses.fields(Outcome)}
    assert fields == {f.name: getattr(built, f.name) for f in dataclasses.fields(Outcome)}
    assert outcome == built and outcome.to_json() == built.to_json()
