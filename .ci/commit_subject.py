"""commit-msg hook: a subject of at most 72 characters, then a blank line before the body."""

import sys

lines = [ln for ln in open(sys.argv[1], encoding="utf-8").read().splitlines() if not ln.startswith("#")] or [""]
if not 0 < len(lines[0]) <= 72 or (len(lines) > 1 and lines[1].strip()):
    sys.exit(f"commit subject: at most 72 characters ({len(lines[0])} here), then a blank line before the body")
