"""Under a flood of frames, the front ends' start-up objects are frozen and full garbage
collections are rare: a full pass over them held the GIL for 25-50 ms, twice a second,
and typed keys waited behind it (benchmarks/console_keys.py measures the effect)."""

from __future__ import annotations

import subprocess
import sys
import textwrap


def test_full_collections_wait_for_many_young_ones_and_skip_the_start_ups_objects() -> None:
    script = textwrap.dedent(
        """
        import gc
        from rac_console.present.heap import FULL_PASS_EVERY, keep_full_collections_rare

        full_passes = []
        gc.callbacks.append(
            lambda phase, info: phase == "stop" and info["generation"] == 2
            and full_passes.append(1)
        )
        before = gc.get_freeze_count()
        keep_full_collections_rare()
        assert gc.get_freeze_count() > before + 1000, gc.get_freeze_count()
        kept = [[n] for n in range(400_000)]  # long-lived: young collections by the hundred
        print(len(full_passes), gc.get_threshold()[2] == FULL_PASS_EVERY)
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["0", "True"]
