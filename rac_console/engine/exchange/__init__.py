"""Talking to the controller: one exchange turned into an outcome, a write as the
target's rules allow it (refused before the wire, confirmed, read back), and a wait for
a condition."""
