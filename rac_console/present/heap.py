"""The garbage collector kept from stalling a front end under a flood of frames.

CPython's full collection walks every object that can hold references. After start-up
that is Textual's or prompt-toolkit's objects and ours (about 60,000), and a frame log
under a flood keeps 20,000 frames more, a few objects each. One full pass then takes
25-50 ms on a 2-core machine, holding the GIL. At 20,000 polls a second the default
thresholds run one twice a second, and a typed key waits behind it: that was the
console's key-to-screen tail (benchmarks/console_keys.py).

So the objects made before the front end runs, which live as long as the program, are
frozen: no pass walks them again. And full passes wait for 100 times as many young
collections as by default. Nothing piles up meanwhile: frames, rows and events hold no
reference cycles, so reference counting frees them (the console's memory stays flat
from 10k to 1M frames: benchmarks/console_bench.py).
"""

from __future__ import annotations

import gc

#: Young (generation 1) collections between two full passes; CPython's default is 10.
FULL_PASS_EVERY = 1000


def keep_full_collections_rare() -> None:
    """Freeze what exists now and make full collections rare (see the module's doc)."""
    gc.freeze()
    young, middle, _ = gc.get_threshold()
    gc.set_threshold(young, middle, FULL_PASS_EVERY)
