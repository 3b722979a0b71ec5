"""What a command or a setting of the config file reaches besides its target: declared
on the command's spec (:class:`~.routing.Traits`) and on the config file's keys
(:mod:`.config_keys`), read in one place by what decides where each may run
(:func:`rac_console.engine.setup.where.reaches`). Pure."""

from __future__ import annotations

from enum import Enum


class Reach(Enum):
    """What a command or a setting reaches besides its target: a console served to a
    browser runs and reads only those that reach nothing else of the machine serving
    it."""

    TARGET = "its target only"
    FILES = "a file on this machine"  # save, load, log, record, transcript; [mqtt] ca_file
    NETWORK = "another host"  # connect, publish; a target's or a cell's publish, [mqtt]
