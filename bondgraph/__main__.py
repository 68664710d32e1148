"""``python -m bondgraph`` and the ``bondgraph`` command.

The interrupt handlers are installed before anything else is imported, so even a Ctrl-C
during start-up ends with one line and status 130 (see :mod:`bondgraph.cli.runner`).
"""
import sys


def run() -> None:
    from .cli import runner

    with runner.handle_signals():
        from .cli import main
        code = main()
    sys.exit(code)


if __name__ == "__main__":
    run()
