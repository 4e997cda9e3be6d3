#!/usr/bin/env bash
# Makes docs/view.png: the default view of `twin view` for the test-12 speed protocol (38 s) with
# the time cursor at 30.5 s (top speed), taken by rerun's headless viewer in a 1920x1080 window.
# Works without a GPU with a software Vulkan driver (Debian: apt-get install mesa-vulkan-drivers);
# the software renderer needs a few minutes for the 38 s recording, hence the long --wait.
# Usage: docs/make_view_png.sh [TWIN]   (TWIN: the twin command, default: twin on PATH)
set -euo pipefail
twin="${1:-twin}"
cd "$(dirname "$0")/.."
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$twin" simulate --test 12 --protocol --no-progress --out "$tmp/protocol.mcap"
"$twin" view "$tmp/protocol.mcap" --screenshot docs/view.png --at 30.5 --wait 600 --window-size 1920x1080
