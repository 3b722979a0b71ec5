"""The shared fixtures come from tests/support (a plugin: ``tests.support.fixtures``).

Every test has a private HOME (the ``env`` fixture); helpers are imported from
``tests.support``, never from another test module (``test_suite_rules.py``)."""

from __future__ import annotations

pytest_plugins = ["tests.support.fixtures"]
