"""Progress lines for ``progress=True``."""

from __future__ import annotations

import sys
import time
from typing import Callable

from ._bisph import Progress

#: Seconds of wall time between two progress lines.
INTERVAL = 2.0


def printer(interval: float = INTERVAL) -> Callable[[Progress], None]:
    """A progress callable that writes a line to ``sys.stderr`` every ``interval`` seconds
    and at the end."""
    last = [float("-inf")]

    def show(p: Progress) -> None:
        now = time.monotonic()
        done = p.time >= p.end
        if now - last[0] < interval and not done:
            return
        last[0] = now
        stage = "settling" if p.settling else "t"
        sys.stderr.write(f"{stage} = {p.time:.4f} / {p.end:.4f} s, step {p.step}\n")
        sys.stderr.flush()

    return show
