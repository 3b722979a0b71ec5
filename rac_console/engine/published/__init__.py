"""What the engine publishes, and the one way it goes out: immutable events (frames,
notes, alerts, results, row views), the status line's figures, what a command says
besides its outcome, and the outbox a front end drains."""
