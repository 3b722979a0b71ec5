"""The library: ``import rac_console as rac`` in a Python script, a front end like the
console, the REPL and the command line.

It composes what they compose (the target's rules from the config file, the session, the
one write path with its refusals, read-back and confirm) and adds only what a Python
caller needs: values as Python types, results as dataclasses, failures as exceptions, a
lock so that threads may share a connection, and an ``asyncio`` face
(:mod:`rac_console.aio`). The public names are exported by ``rac_console`` itself.
"""
