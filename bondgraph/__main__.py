"""``python -m bondgraph`` is the ``bondgraph`` command."""
import sys

from .cli import main

sys.exit(main())
