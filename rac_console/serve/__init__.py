"""``rac-console serve``: the console in a browser, behind a token, a cookie and checks of
Host and Origin (``pip install "rac-console[web]"``).

- :mod:`.command`: the command each session runs (argv, no shell), and whether this
  process is such a session (no third-party import: the CLI reads it at every start);
- :mod:`.guard`: who may come in, pure: the token, the cookie, the Host allow-list, the
  Origin, the session slots;
- :mod:`.textual_serve_parts`: the one module that touches textual-serve's private parts,
  with the versions it was checked against;
- :mod:`.server`: the aiohttp application put together, the URL printed, run until
  stopped.

Importing this package imports nothing: aiohttp and textual-serve come with the modules
that need them.
"""
