"""The outcome of an answered exchange, filled in one step on the hot path, is the same
object as one built field by field: equal, frozen, with every field."""

from __future__ import annotations

import dataclasses

import pytest

from rac_console.commands.language import Get, VarRef
from rac_console.commands.outcome import ExitStatus, Outcome, answered
from rac_console.engine.execute import execute
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
    assert set(vars(outcome)) == {f.name for f in dataclasses.fields(Outcome)}
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


def test_answered_sets_every_field() -> None:
    made = answered("GET:RC8:1:I:", ExitStatus.OK, None, "0,3,1", None, 0.1, None, None, None)  # type: ignore[arg-type]
    assert list(vars(made)) == [f.name for f in dataclasses.fields(Outcome)]
