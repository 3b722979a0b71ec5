"""What the tests share, so that no test module imports another.

- :mod:`tests.support.fixtures`: the shared fixtures, a pytest plugin (registered by
  ``tests/conftest.py``): the private environment (``env``), ``recording`` servers, the
  engine's ``front``, a tmux ``terminal``, ``utc``, a CLI ``config`` file, an MQTT
  ``broker`` with its ``subscriber``, commands left ``running``;
- :mod:`tests.support.drivers`: the front ends as a test drives them: the console
  (Pilot), the REPL (on a pipe), the CLI (a subprocess), the engine alone, the console
  in tmux and in a pty;
- :mod:`tests.support.servers`: the servers the tests write: a scripted controller that
  answers lines (:class:`~tests.support.servers.RecordingServer`, its variants by
  parameter), a valve before the simulator, an asyncio one run by a handler;
- :mod:`tests.support.brokers`: a real mosquitto and its subscriber, a pullable cable,
  and brokers that lie;
- :mod:`tests.support.cells`: the console and a front in miniature on a cell;
- :mod:`tests.support.sessions`: the blocking session driven from asyncio tests;
- :mod:`tests.support.samples`: the vendor's sample exchanges, statuses to present.
- :mod:`tests.support.doc_samples`: the docs' marked sample sessions, and how they are
  compared with what the program prints.

Nothing here is collected as tests; every module is typed strictly (``mypy tests``).
"""
