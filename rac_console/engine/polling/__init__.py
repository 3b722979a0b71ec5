"""Polling the watched rows: which row is next and when, the backoff after a failure,
the one session to the target and its health, and the publisher that hands what the
engine sees to the outbox, the frame files and the plant."""
