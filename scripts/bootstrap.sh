#!/usr/bin/env bash
# Prepare everything ontodetect needs on a fresh machine: the system library Open3D loads
# (libusb-1.0), a virtual environment in .venv, and the package with its dev extras, every
# dependency at the exact version and hash requirements.lock gives (`make lock` refreshes it).
# Safe to run again: it only reinstalls when pyproject.toml or the lock has changed.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
PYTHON=${PYTHON:-python3}
VENV=${VENV:-.venv}

say() { printf '[setup] %s\n' "$*" >&2; }

# Optional parts: --with-browser (the test suite's viewer test), --with-furniture (the
# generalization benchmark). The demo needs neither.
with_browser=0
with_furniture=0
for arg in "$@"; do
    case "$arg" in
        --with-browser) with_browser=1 ;;
        --with-furniture) with_furniture=1 ;;
        *) say "unknown option $arg (use --with-browser, --with-furniture)"; exit 2 ;;
    esac
done

# 1. libusb-1.0: Open3D's Python module links against it even in the CPU build.
if [ "$(uname -s)" = "Linux" ] && ! ldconfig -p 2>/dev/null | grep -q 'libusb-1\.0\.so\.0'; then
    if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
        say "installing libusb-1.0-0 with apt-get (Open3D needs it)"
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -qq >/dev/null
        apt-get install -y -qq libusb-1.0-0 >/dev/null
    else
        say "Open3D needs the system library libusb-1.0, which is missing."
        say "Install it first, e.g.: sudo apt-get install libusb-1.0-0 (Debian/Ubuntu)"
        say "                    or: sudo dnf install libusbx (Fedora)"
        exit 1
    fi
fi

# 1a. With --with-browser (make test): Chromium, in which the viewer's test
#     (tests/test_viewer.py) opens view.html headless. Only installed when missing and
#     apt-get can; the test installs it the same way.
if [ "$with_browser" = 1 ] && [ "$(uname -s)" = "Linux" ] && ! command -v chromium >/dev/null 2>&1 \
        && [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    say "installing chromium with apt-get (the viewer's browser test)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null
    apt-get install -y -qq chromium >/dev/null || say "chromium could not be installed"
fi

# 1b. With --with-furniture (the generalization benchmark): Debian's Sweet Home 3D furniture
#     catalogues, which furnish its simulated rooms. Unit tests never need them.
if [ "$with_furniture" = 1 ] && [ ! -d /usr/share/sweethome3d/furniture ] \
        && [ -z "${ONTODETECT_SH3D_DIR:-}" ]; then
    if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
        say "installing sweethome3d-furniture with apt-get (the benchmark's furniture models)"
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -qq >/dev/null
        apt-get install -y -qq sweethome3d-furniture >/dev/null
    else
        say "The generalization benchmark furnishes its rooms with Sweet Home 3D's catalogues."
        say "Install them first: sudo apt-get install sweethome3d-furniture (Debian/Ubuntu),"
        say "or point ONTODETECT_SH3D_DIR at a folder of .sh3f files."
        exit 1
    fi
fi

# 2. The virtual environment.
if [ ! -x "$VENV/bin/python" ]; then
    say "creating virtual environment in $VENV"
    "$PYTHON" -m venv "$VENV"
fi

# 3. Dependencies from the lock (exact versions, hashes checked), then the package itself
#    without resolving anything again; reinstalled only when the metadata or the lock changed.
stamp="$VENV/.ontodetect-installed"
want=$(cat pyproject.toml requirements.lock | sha256sum | cut -d' ' -f1)
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
    say "installing the locked dependencies into $VENV (requirements.lock)"
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check --require-hashes -r requirements.lock
    say "installing ontodetect into $VENV"
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check --no-deps \
        --no-build-isolation -e .
    "$VENV/bin/python" -m pip check >/dev/null || {
        say "the installed packages do not fit together:"; "$VENV/bin/python" -m pip check; exit 1; }
    echo "$want" > "$stamp"
fi
"$VENV/bin/python" -c "import open3d, ontodetect" >/dev/null
say "ready: $VENV/bin/ontodetect"
