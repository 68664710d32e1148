"""A page opened in a real headless browser: Debian's Chromium driven by playwright.

:func:`open_page` loads a local HTML file with every request that would leave the file
system blocked and recorded, and collects the console's messages and the page's uncaught
errors, so a test can assert that a page is self-contained and loads cleanly, then query its
DOM and take a screenshot.  Without Chromium the test is skipped, except in CI, where
``.ci/run`` installs it and its absence is a failure.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

#: flags that keep a headless Chromium quiet and off the network
ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


@dataclass
class Log:
    """What the page said and tried: console messages (type, text), uncaught errors, and the
    requests that would have left the file system (blocked)."""

    console: list[tuple[str, str]] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    outside: list[str] = field(default_factory=list)

    def problems(self) -> list[str]:
        """Console errors and warnings, uncaught errors, and requests off the file system."""
        return (
            [f"console {kind}: {text}" for kind, text in self.console if kind in ("error", "warning")]
            + [f"uncaught: {e}" for e in self.errors]
            + [f"request: {u}" for u in self.outside]
        )


def chromium() -> str:
    """The path of Debian's Chromium, or skip (fail in CI: .ci/run installs it)."""
    path = shutil.which("chromium") or shutil.which("chromium-browser")
    if path is None:
        if os.environ.get("CI"):
            pytest.fail("Chromium is not installed (.ci/run installs it with apt-get)")
        pytest.skip("Chromium is not installed: apt-get install chromium")
    return path


@contextlib.contextmanager
def open_page(path: Path, width: int = 1200, height: int = 900, wait_for: str = "canvas"):
    """Open the local file ``path`` headless; yields ``(page, log)`` once ``wait_for`` is visible."""
    sync = pytest.importorskip("playwright.sync_api")
    exe = chromium()
    log = Log()

    def route(r):
        if r.request.url.startswith("file:"):
            r.continue_()
        else:
            log.outside.append(r.request.url)
            r.abort()

    with sync.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=exe, args=ARGS)
        try:
            page = browser.new_page(viewport={"width": width, "height": height})
            page.on("console", lambda m: log.console.append((m.type, m.text)))
            page.on("pageerror", lambda e: log.errors.append(str(e)))
            page.route("**/*", route)
            page.goto(Path(path).resolve().as_uri())
            page.wait_for_selector(wait_for, timeout=30_000)
            page.wait_for_load_state("networkidle")
            yield page, log
        finally:
            browser.close()


def assert_plots_drawn(png, steps: int = 1) -> None:
    """The screenshot holds the measured curve (dark grey), the calibrated model (blue) and the
    model after the last of ``steps`` named steps (drawn last, over the others: the palette's
    colour ``steps + 1``) over many pixels, not a blank page."""
    from PIL import Image

    from bondgraph.plotting.html_report import PALETTE

    rgb = np.asarray(Image.open(png).convert("RGB")).reshape(-1, 3).astype(int)
    for colour in (PALETTE[0], PALETTE[1], PALETTE[(steps + 1) % len(PALETTE)]):
        target = np.array([int(colour[i : i + 2], 16) for i in (1, 3, 5)])
        assert np.sum(np.abs(rgb - target).sum(axis=1) < 30) > 500, colour
