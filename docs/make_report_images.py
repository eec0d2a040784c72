"""Regenerate the replay-report pictures in docs/img/ (not a test; docs/capture.md shows them):

    PYTHONPATH=src python docs/make_report_images.py

It does what docs/capture.md "Conformance runs" describes, with real processes: `opentmcl serve`
plays a "real" module from a profile with planted differences (tests/capture/recorder.py PLANTED),
`opentmcl conform --allow-motion` checks it against the TMCM-6212 and writes the HTML report, and
headless Chromium (Playwright, /usr/bin/chromium) photographs three parts of the page:
report-causes.png (root causes and agreement by area), report-moves.png (move durations) and
report-plots.png (position and speed, module against twin). Run over TCP on a real clock, so the
numbers differ a little from run to run.
"""
from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
IMG = ROOT / "docs" / "img"
sys.path.insert(0, str(ROOT))
from tests.capture.recorder import PLANTED  # noqa: E402  (the planted profile of the tests)


def serve(profile: Path) -> tuple[subprocess.Popen, str]:
    proc = subprocess.Popen([sys.executable, "-m", "opentmcl", "serve", "--module", str(profile), "--tcp",
                             "127.0.0.1:0", "--idle-timeout", "0"], stdout=subprocess.PIPE)
    deadline, buf = time.monotonic() + 30, b""
    while b"Press Ctrl-C" not in buf:
        ready, _, _ = select.select([proc.stdout], [], [], max(0.0, deadline - time.monotonic()))
        if not ready:
            proc.kill()
            raise SystemExit("serve did not start")
        buf += os.read(proc.stdout.fileno(), 4096)
    url = next(line.split()[1] for line in buf.decode().splitlines() if line.strip().startswith("tcp "))
    return proc, url


def main() -> None:
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as tmp:
        profile = Path(tmp) / "planted.toml"
        profile.write_text(PLANTED)
        proc, url = serve(profile)
        try:
            subprocess.run([sys.executable, "-m", "opentmcl", "conform", url, "--module", "TMCM-6212",
                            "--allow-motion", "--max-travel", "20000", "--axes", "0", "--max-speed", "40000",
                            "--max-accel", "204800", "--capture", str(Path(tmp) / "conform.jsonl"),
                            "--html", str(Path(tmp) / "html")], check=False, timeout=600)
        finally:
            proc.send_signal(signal.SIGTERM)
            proc.wait(timeout=20)
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path="/usr/bin/chromium",
                                         args=["--headless", "--no-sandbox", "--disable-gpu"])
            page = browser.new_page(viewport={"width": 1300, "height": 900})
            page.goto((Path(tmp) / "html" / "index.html").as_uri())
            top = page.locator("h1").bounding_box()
            areas = page.locator("#areas").bounding_box()
            page.screenshot(path=str(IMG / "report-causes.png"), clip={
                "x": 0, "y": top["y"] - 10, "width": 1300, "height": min(900, areas["y"] + areas["height"] - top["y"] + 20)})
            page.locator("#moves").screenshot(path=str(IMG / "report-moves.png"))
            page.locator("#plots").screenshot(path=str(IMG / "report-plots.png"))
            browser.close()
    print("wrote", ", ".join(f"docs/img/report-{n}.png" for n in ("causes", "moves", "plots")))


if __name__ == "__main__":
    main()
