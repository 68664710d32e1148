"""The measured-data CSV format: its grammar, shared by the reader and the writer.

::

    # actuator: APA120ML                    <- "# key: value" comments are metadata
    # sensor: capacitive, 10 kHz
    t,V,x                                   <- exactly one header line
    0,0,0
    0.0001,0.5,1.2e-08                      <- numeric rows; comments may sit between rows
    ...

* UTF-8 (a byte-order mark is tolerated), LF or CRLF line endings, comma-separated.
* Lines whose first non-blank character is ``#`` are comments, before or between rows.  A
  comment of the form ``# key: value`` (the key starts with a letter or ``_`` and runs to
  the first ``:``; it holds no ``#``) is metadata, e.g. ``# param k1: 2.5e6``; key and value
  are stripped of surrounding blanks.  If a key repeats, the last value wins.  Blank lines
  are ignored.
* The header names the columns; names are stripped of blanks (and of one pair of enclosing
  double quotes).  ``t`` is time in seconds, strictly increasing; the other columns are the
  model's inputs and outputs in SI units (e.g. ``V`` in volts, ``x`` in metres); columns no
  model uses are kept.
* Cells are plain decimal numbers (``1``, ``-2.5``, ``.5``, ``3e-6``); NaN and inf are
  refused, and so is everything listed in :func:`~bondgraph.data.read_csv`.

Every problem in a file is a :class:`~bondgraph.support.errors.DataError` whose message is one line
``FILE:LINE: problem; fix`` (``LINE`` 1-based, as an editor counts, with CR, LF and CRLF
each ending one line).  ``docs/data-format.md`` is the user-facing description.
"""

from __future__ import annotations

import re

# A number cell as numpy's parser accepts it: decimal, optional exponent, or nan/inf (which
# are then refused with their own message).  Anything else is "non-numeric".
NUMBER = re.compile(
    r"[ \t]*[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?|nan)[ \t]*",
    re.IGNORECASE | re.ASCII,
)
# "# key: value": the key starts with a letter or "_" and runs to the first ":" (no "#").
META = re.compile(r"#\s*([^\W\d][^:#]*?)\s*:(.*)")
# a metadata key the writer may write so that META reads it back unchanged
META_KEY = re.compile(r"[^\W\d](?:[^:#\n\r]*[^:#\s])?")
