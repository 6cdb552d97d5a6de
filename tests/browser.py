"""Open a local HTML file in headless Chromium (Debian's /usr/bin/chromium) through Playwright.

Used by the report tests to see the page as a user does: console errors, images that loaded
with a non-zero size, and a screenshot kept as a test artefact.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass
from pathlib import Path

import pytest

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARTIFACTS = Path(__file__).resolve().parents[1] / "test-artifacts"
FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


@dataclass(frozen=True)
class PageView:
    """What the page showed: console errors, every image (``alt``, ``complete``, natural
    ``width``/``height``, and ``box``: its displayed ``x``, ``y``, ``w``, ``h`` in CSS pixels),
    the page's visible text, its width and a full-page screenshot."""

    console_errors: list[str]
    images: list[dict]
    screenshot: Path
    text: str = ""
    page_width: int = 0

    def overlapping_images(self) -> list[tuple[str, str]]:
        """Pairs of images whose displayed boxes overlap."""
        boxes = [(img["alt"], img["box"]) for img in self.images]
        return [
            (a, b)
            for i, (a, p) in enumerate(boxes)
            for b, q in boxes[i + 1 :]
            if p["x"] < q["x"] + q["w"]
            and q["x"] < p["x"] + p["w"]
            and p["y"] < q["y"] + q["h"]
            and q["y"] < p["y"] + p["h"]
        ]


def require_chromium() -> None:
    """Skip on a developer machine without Chromium; fail on CI, where `make test` installs it."""
    if not Path(CHROMIUM).exists():
        message = f"Chromium not found at {CHROMIUM} (make test installs Debian's chromium)"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)


def view(page_path: Path, screenshot_name: str) -> PageView:
    """Load ``page_path`` headless and report console errors, images and a screenshot."""
    require_chromium()
    from playwright.sync_api import sync_playwright

    ARTIFACTS.mkdir(exist_ok=True)
    shot = ARTIFACTS / screenshot_name
    errors: list[str] = []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=FLAGS)
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(page_path.resolve().as_uri(), wait_until="load")
        images = page.eval_on_selector_all(
            "img",
            "els => els.map(e => { const r = e.getBoundingClientRect();"
            " return {alt: e.alt, complete: e.complete, width: e.naturalWidth,"
            " height: e.naturalHeight, box: {x: r.x, y: r.y, w: r.width, h: r.height}}; })",
        )
        text = page.inner_text("body")
        width = page.evaluate("document.documentElement.scrollWidth")
        page.screenshot(path=str(shot), full_page=True)
        browser.close()
    return PageView(errors, images, shot, text, width)
