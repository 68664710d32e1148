"""The scoring rule: a diagnosis (the JSON of ``bondgraph diagnose --json``) against a truth label.

* An effect-free record (``cause`` ``none``) is right when the diagnosis names no cause; any
  named cause is a false alarm.
* A record with an effect is right when the first named cause equals the truth's ``cause``;
  for ``higher-mode`` with ``count`` n the first named cause must be ``higher-mode`` and the
  chain must name ``higher-mode`` at least n times.
* The site is scored apart: on the step that names the truth's cause (the first step; for
  ``higher-mode``, any step naming it), its ``site`` must equal the truth's site or one of its
  aliases (``drive``, the source element and the input name for a drive site; the output's
  name and ``sensor`` for a drift), as a whole word of the diagnosis' text.  A step without a
  ``site`` is ``unknown``; when no step names the truth's cause the site is wrong.
* A diagnosis that failed (no JSON, an error) is an error row: wrong, site wrong.
* A record whose effect failed the visibility rule (``visible`` false) is scored but kept out
  of the accuracy (see :func:`summarise`).
"""

from __future__ import annotations

import re
from collections import Counter

SITE_UNKNOWN = "unknown"


def _site_matches(named: str, accepted) -> bool:
    text = str(named).strip().lower()
    for alias in accepted:
        a = str(alias).strip().lower()
        if a and (text == a or re.search(rf"(?<![\w.]){re.escape(a)}(?![\w])", text)):
            return True
    return False


def score(truth: dict, diagnosis: dict | None) -> dict:
    """Score one record.

    Parameters
    ----------
    truth : dict
        The truth label (``*.truth.json``): ``cause``, ``site``, ``site_aliases``, ``count``.
    diagnosis : dict or None
        The diagnosis JSON (``causes``, ``steps`` with ``cause`` and optional ``site``), or
        None (or a dict with ``error``) when the diagnosis failed.

    Returns
    -------
    dict
        ``right`` (bool), ``site_right`` (True, False, ``"unknown"``, or None for an
        effect-free record), ``first`` (the first named cause or ``none``), ``named`` (the
        chain), ``error`` (the failure, or None).
    """
    cause = truth["cause"]
    if diagnosis is None or "error" in diagnosis:
        err = "no diagnosis" if diagnosis is None else str(diagnosis["error"])
        return {
            "right": False,
            "site_right": None if cause == "none" else False,
            "first": "error",
            "named": [],
            "error": err,
        }
    named = list(diagnosis.get("causes") or [])
    first = named[0] if named else "none"
    if cause == "none":
        return {"right": not named, "site_right": None, "first": first, "named": named, "error": None}
    if cause == "higher-mode":
        right = first == "higher-mode" and named.count("higher-mode") >= int(truth.get("count", 1))
    else:
        right = first == cause
    steps = list(diagnosis.get("steps") or [])
    if cause == "higher-mode":
        candidates = [s for s in steps if s.get("cause") == cause]
    else:
        candidates = steps[:1] if steps and steps[0].get("cause") == cause else []
    accepted = truth.get("site_aliases") or [truth.get("site")]
    if not candidates:
        site_right = False
    elif all("site" not in s or s.get("site") in (None, "") for s in candidates):
        site_right = SITE_UNKNOWN
    else:
        site_right = any(_site_matches(s["site"], accepted) for s in candidates if s.get("site"))
    return {"right": bool(right), "site_right": site_right, "first": first, "named": named, "error": None}


def summarise(rows: list[dict]) -> dict:
    """Accuracy, false alarms, site matches and the confusion matrix over scored rows.

    Each row holds ``truth`` (the cause), ``visible`` and the fields of :func:`score`.
    Rows whose effect is not visible are counted apart (``invisible``) and left out of
    every other figure.
    """
    kept = [r for r in rows if r.get("visible", True)]
    confusion: dict = {}
    for r in kept:
        confusion.setdefault(r["truth"], Counter())[r["first"]] += 1
    effects = [r for r in kept if r["truth"] != "none"]
    nones = [r for r in kept if r["truth"] == "none"]
    sites = Counter(str(r["site_right"]) for r in effects)
    return {
        "records": len(rows),
        "scored": len(kept),
        "invisible": len(rows) - len(kept),
        "right": sum(r["right"] for r in kept),
        "errors": sum(r["first"] == "error" for r in kept),
        "effects_right": sum(r["right"] for r in effects),
        "effects": len(effects),
        "false_alarms": sum(not r["right"] for r in nones),
        "effect_free": len(nones),
        "site_right": sites.get("True", 0),
        "site_wrong": sites.get("False", 0),
        "site_unknown": sites.get(SITE_UNKNOWN, 0),
        "confusion": {k: dict(v) for k, v in sorted(confusion.items())},
    }
