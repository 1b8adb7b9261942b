#!/usr/bin/env bash
# Screenshots of every windowed example on a machine with no display or GPU: a real X
# window under Xvfb, rendered by Mesa's software Vulkan driver (lavapipe), saved through
# Bevy's screenshot API after a number of frames (STRANDS_SCREENSHOT, see
# app/src/window/screenshot.rs). Then one scripted drag: xdotool grabs a particle of the
# resting long strand and pulls it up, and the display is captured mid-drag.
#
# Usage: scripts/screenshots.sh [output directory, default screenshots/]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-screenshots}
frames=${STRANDS_SCREENSHOT_FRAME:-120}

missing=0
for tool in xvfb-run Xvfb xdotool import; do
    command -v "$tool" >/dev/null 2>&1 || missing=1
done
[ -e /usr/share/vulkan/icd.d/lvp_icd.x86_64.json ] || missing=1
if [ "$missing" = 1 ]; then
    apt-get update
    apt-get install -y --no-install-recommends xvfb xauth mesa-vulkan-drivers libvulkan1 \
        libxkbcommon-x11-0 libxcursor1 libxi6 libx11-xcb1 xdotool imagemagick
fi

cargo build --examples --features render,avian,rapier
export VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
export VK_ICD_FILENAMES=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
export WGPU_BACKEND=vulkan
mkdir -p "$out"

for example in long_strand spaghetti_factory meatball_factory furry_creature branches sandbox game physics_world rapier_world; do
    echo "== $example"
    STRANDS_SCREENSHOT="$out/$example.png" STRANDS_SCREENSHOT_FRAME="$frames" \
        xvfb-run -a -s '-screen 0 1280x720x24' "target/debug/examples/$example" \
        > "$out/$example.log" 2>&1
    echo "   $out/$example.png"
done

echo "== drag (long_strand)"
display=:77
Xvfb "$display" -screen 0 1280x720x24 -nolisten tcp > "$out/xvfb.log" 2>&1 &
xvfb=$!
trap 'kill "$app" "$xvfb" 2>/dev/null || true' EXIT
sleep 1
DISPLAY="$display" target/debug/examples/long_strand > "$out/drag.log" 2>&1 &
app=$!
DISPLAY="$display" timeout 120 xdotool search --sync --onlyvisible --name "bevy_strands" > /dev/null
# Let the strand land and settle on the floor (the simulation runs in real time).
sleep 8
# The box fills the 720-pixel height left of the panel: floor at y ≈ 689, x ≈ 600 is
# about 0.69 along the floor, where the settled strand lies.
DISPLAY="$display" xdotool mousemove 600 689 mousedown 1
for y in $(seq 680 -20 300); do
    DISPLAY="$display" xdotool mousemove 600 "$y"
    sleep 0.1
done
sleep 1.5
import -display "$display" -window root "$out/drag.png"
DISPLAY="$display" xdotool mouseup 1
echo "   $out/drag.png"
kill "$app"
wait "$app" 2>/dev/null || true

echo "== tools (sandbox)"
DISPLAY="$display" target/debug/examples/sandbox > "$out/tools.log" 2>&1 &
app=$!
DISPLAY="$display" timeout 120 xdotool search --sync --onlyvisible --name "bevy_strands" > /dev/null
sleep 3
# The tool buttons sit in a row of the panel (y ≈ 493): hair at x ≈ 1143, particle at
# x ≈ 1048. Draw a hair rooted at the top left, sweeping right and down.
DISPLAY="$display" xdotool mousemove 1143 493 click 1
sleep 0.5
DISPLAY="$display" xdotool mousemove 250 150 mousedown 1
for step in $(seq 1 30); do
    DISPLAY="$display" xdotool mousemove $((250 + step * 10)) $((150 + step * 4))
    sleep 0.05
done
DISPLAY="$display" xdotool mouseup 1
sleep 0.5
DISPLAY="$display" xdotool mousemove 1048 493 click 1
sleep 0.5
# Input is read once a frame: pause between clicks so each lands in a frame of its own.
DISPLAY="$display" xdotool mousemove 650 300 click 1
sleep 0.5
DISPLAY="$display" xdotool mousemove 700 250 click 1
sleep 2
import -display "$display" -window root "$out/tools.png"
echo "   $out/tools.png"
