"""``python -m bondgraph`` and the ``bondgraph`` command.

A Ctrl-C (or SIGTERM) handler is the very first thing installed, so even an interrupt during
start-up ends with one line and status 130 (143); :mod:`bondgraph.support.interrupt` then takes over.
"""

import os
import signal
import sys


def _early(signum, frame):  # noqa: ARG001 - before any work: nothing to clean up
    os.write(2, b"bondgraph: interrupted; no output file was changed\n")
    os._exit(130 if signum == signal.SIGINT else 143)


def run() -> None:
    signal.signal(signal.SIGINT, _early)
    signal.signal(signal.SIGTERM, _early)
    from .support import interrupt

    with interrupt.handle_signals():
        from .cli import main

        code = main()
    sys.exit(code)


if __name__ == "__main__":
    run()
