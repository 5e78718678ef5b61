"""Screenshot of a `socialzoo replay` page with headless Chromium (for docs/viewer.png).

    python tools/viewer_screenshot.py episode.html docs/viewer.png --step 900 --camera follow

Needs Debian's chromium (/usr/bin/chromium; `make test` installs it) and the playwright package
(the dev extra); never `playwright install`.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("page", type=Path, help="the replay .html file")
    parser.add_argument("out", type=Path, help="the .png to write")
    parser.add_argument("--step", type=int, default=0, help="clock step to show")
    parser.add_argument("--camera", choices=("follow", "map"), default="follow")
    parser.add_argument("--width", type=int, default=1280, help="viewport width, pixels")
    parser.add_argument("--height", type=int, default=900, help="viewport height, pixels")
    parser.add_argument("--chromium", default="/usr/bin/chromium", help="the browser binary")
    args = parser.parse_args()

    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as profile, sync_playwright() as p:
        context = p.chromium.launch_persistent_context(
            profile,
            executable_path=args.chromium,
            headless=True,
            args=FLAGS,
            viewport={"width": args.width, "height": args.height},
            device_scale_factor=1,
        )
        page = context.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(args.page.resolve().as_uri())
        page.wait_for_function("document.body.dataset.ready === 'true'", timeout=30_000)
        page.evaluate(f"window.socialzooReplay.setCamera('{args.camera}')")
        page.evaluate(f"window.socialzooReplay.seek({args.step})")
        args.out.parent.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(args.out), full_page=True)
        context.close()
    if errors:
        raise SystemExit(f"page errors: {errors}")
    print(f"{args.out}: {args.out.stat().st_size / 1e3:.0f} kB")


if __name__ == "__main__":
    main()
