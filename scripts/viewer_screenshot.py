"""A picture of ``view.html`` as a browser draws it: the README's viewer screenshot.

Writes OUT_DIR/view.html (``ontodetect view``), opens it in headless Chromium and saves a
screenshot, reduced to a 256-colour palette so that it stays small in the repository.

    ontodetect demo -o demo-output
    python scripts/viewer_screenshot.py demo-output docs/images/viewer.png
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import tempfile
from pathlib import Path

from ontodetect.render import CHROMIUM_FLAGS, write_viewer


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir", type=Path, help="a folder written by 'ontodetect detect'")
    parser.add_argument("png", type=Path, help="picture to write")
    parser.add_argument("--size", default="1100,700", help="window width,height in pixels")
    parser.add_argument("--hide", default="", help="classes to switch off, e.g. 'other points'")
    parser.add_argument("--colors", type=int, default=256, help="palette size (0: full colour)")
    args = parser.parse_args()
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        parser.error("chromium is not installed (scripts/bootstrap.sh --with-browser)")
    page = write_viewer(args.out_dir).resolve().as_uri()
    if args.hide:
        page += "#hide=" + args.hide
    with tempfile.TemporaryDirectory() as profile:
        shot = Path(profile) / "shot.png"
        subprocess.run(
            [
                browser,
                *CHROMIUM_FLAGS,
                f"--user-data-dir={profile}",
                f"--window-size={args.size}",
                f"--screenshot={shot}",
                page,
            ],
            check=True,
            capture_output=True,
            timeout=120,
        )
        if args.colors:
            from PIL import Image

            image = Image.open(shot).convert("RGB").quantize(colors=args.colors)
            args.png.parent.mkdir(parents=True, exist_ok=True)
            image.save(args.png, optimize=True)
        else:
            shutil.copyfile(shot, args.png)
    print(f"wrote {args.png} ({args.png.stat().st_size:,} bytes)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
