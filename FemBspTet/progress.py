# SPDX-License-Identifier: LGPL-2.1-or-later
"""A progress bar on stderr that appears only for runs longer than a second.

``Progress(enabled=True)`` is called with ``(stage, fraction)``; it draws nothing during the first
second (short runs stay silent), then redraws at most ten times a second. ``--quiet`` disables it.
"""

import sys
import time


class Progress:
    def __init__(self, enabled=True, stream=None, delay=1.0):
        self.enabled = enabled
        self.stream = stream if stream is not None else sys.stderr
        self.start = time.monotonic()
        self.delay = delay
        self._last_draw = 0.0
        self._drawn = False
        self.stage = ""

    def __call__(self, stage, fraction=None):
        self.stage = stage
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self.start < self.delay or now - self._last_draw < 0.1:
            return
        self._last_draw = now
        width = 30
        if fraction is None:
            bar = "." * width
            pct = "    "
        else:
            fraction = min(max(float(fraction), 0.0), 1.0)
            filled = int(round(fraction * width))
            bar = "#" * filled + "-" * (width - filled)
            pct = f"{int(fraction * 100):3d}%"
        elapsed = now - self.start
        self.stream.write(f"\r[{bar}] {pct} {stage[:40]:<40s} {elapsed:6.1f} s")
        self.stream.flush()
        self._drawn = True

    def finish(self):
        if self.enabled and self._drawn:
            self.stream.write("\n")
            self.stream.flush()
            self._drawn = False
