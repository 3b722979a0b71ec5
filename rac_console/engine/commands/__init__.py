"""Commands as the engine runs them: each declared once (the registry), what a handler
may use (its context, over an engine or over a plain session), the job runner every
front end shares, and the built-in commands (:mod:`.builtin`)."""
