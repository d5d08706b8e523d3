# SPDX-License-Identifier: LGPL-2.1-or-later
"""Progress of a command-line run on stderr, by stage; silent for runs shorter than a second.

``Progress(enabled=True)`` is called with ``(stage, fraction)`` (fraction in 0..1 or None when
the stage cannot tell). A stage's shown fraction never goes back, also when the stage comes
again after others (the bar redraws ten times a second, so a short stage in between may never
be seen: the same name must not show a smaller percentage); a new stage starts at 0.

* stderr is a terminal: one line that fits the terminal's width, drawn by ``rich`` (Debian's
  ``python3-rich``): the stage's name, a bar and its percentage, the elapsed seconds. It appears
  after ``delay`` seconds and is erased when the run ends (``finish``).
* stderr is not a terminal (a log file, a pipe, CI): plain lines, one per stage as it starts
  (``fembsptet: stage (1.2 s)``), no control characters.

``note(text)`` prints a message on its own line (above the bar on a terminal). ``--quiet``
disables everything but the notes' callers' own messages.
"""

import sys
import time


class Progress:
    def __init__(self, enabled=True, stream=None, delay=1.0):
        self.enabled = enabled
        self.stream = stream if stream is not None else sys.stderr
        self.delay = delay
        self.start = time.monotonic()
        self.stage = ""
        self.fraction = 0.0
        self._reached = {}  # stage -> largest fraction reported for it
        self._shown_stage = None
        try:
            self._terminal = bool(self.stream.isatty())
        except (AttributeError, ValueError):
            self._terminal = False
        self._live = None  # rich Progress once drawn
        self._task = None

    def __call__(self, stage, fraction=None):
        if stage != self.stage:
            self.stage, self.fraction = stage, self._reached.get(stage, 0.0)
        if fraction is not None:
            self.fraction = max(self.fraction, min(max(float(fraction), 0.0), 1.0))
        self._reached[stage] = self.fraction
        if not self.enabled:
            return
        elapsed = time.monotonic() - self.start
        if elapsed < self.delay:
            return
        if not self._terminal:
            if self._shown_stage != self.stage:
                self._shown_stage = self.stage
                self.stream.write(f"fembsptet: {self.stage} ({elapsed:.1f} s)\n")
                self.stream.flush()
            return
        self._draw(fraction is not None)

    def _draw(self, known):
        if self._live is None:
            from rich.console import Console
            from rich.progress import (BarColumn, Progress as RichProgress, TaskProgressColumn,
                                       TextColumn, TimeElapsedColumn)

            console = Console(file=self.stream)
            self._live = RichProgress(
                TextColumn("[bold]fembsptet[/bold] {task.description}"), BarColumn(),
                TaskProgressColumn(), TimeElapsedColumn(), console=console, transient=True,
                refresh_per_second=10)
            self._live.start()
            self._task = self._live.add_task(self.stage, total=100.0)
            # the elapsed time counts from the start of the run, not from the first drawing
            self._live.tasks[0].start_time = self._live.get_time() - (time.monotonic()
                                                                       - self.start)
        completed = 100.0 * self.fraction
        self._live.update(self._task, description=self.stage[:40], completed=completed)
        # a stage that gives no fraction shows a pulsing bar and no percentage
        self._live.tasks[0].total = 100.0 if known or completed else None

    def note(self, text):
        """``text`` on its own line (above the bar while it is drawn)."""
        if self._live is not None:
            self._live.console.print(text, markup=False, highlight=False, soft_wrap=True)
        else:
            self.stream.write(text + "\n")
            self.stream.flush()

    def finish(self):
        """Erase the bar (terminal); the next call starts drawing again."""
        if self._live is not None:
            self._live.stop()
            self._live = None
            self._task = None
