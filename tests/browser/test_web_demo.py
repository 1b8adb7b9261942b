#!/usr/bin/env python3
"""The web demo in a real browser: headless Chromium driven by Playwright.

Serves the folder scripts/web.sh wrote, opens each factory and the rope, lets each run
a few simulated seconds, and checks what a visitor would see: frames drawn (a
screenshot that is not blank), the live figures the page receives (finite, every edge
within 1e-9 of its length, no crossing, particles arriving), a rope dragged by the
mouse, and the page's own panel (pause, step, run, the step size, a tool, a bad command
refused with its reason, the scene switched in place), and an unknown scene in the
address (the first scene shown, the reason in the browser's console). Prints each scene's figures,
real-time factor included.

Usage: python3 tests/browser/test_web_demo.py [folder, default target/web-demo]
Needs the Python package playwright and Debian's chromium (/usr/bin/chromium); it never
downloads a browser of its own.
"""

import functools
import http.server
import json
import pathlib
import struct
import sys
import threading
import time
import zlib

from playwright.sync_api import sync_playwright

ERROR_BOUND = 1e-9
CHROMIUM = "/usr/bin/chromium"
# Software WebGL2 (SwiftShader), and none of the background traffic a closed network
# refuses.
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--ignore-gpu-blocklist",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-quic",
    "--no-first-run",
]
VIEWPORT = {"width": 1280, "height": 720}
# Generous: a cold page compiles tens of megabytes of wasm, and software WebGL is slow.
LOAD_TIMEOUT = 240.0
RUN_TIMEOUT = 600.0


class Failure(Exception):
    pass


def check(condition, message):
    if not condition:
        raise Failure(message)


def serve(folder):
    """A static server on a free loopback port, in a thread; returns it and its URL."""

    class Handler(http.server.SimpleHTTPRequestHandler):
        extensions_map = {
            **http.server.SimpleHTTPRequestHandler.extensions_map,
            ".wasm": "application/wasm",
            ".js": "text/javascript",
        }

        def log_message(self, *args):
            pass

    handler = functools.partial(Handler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server, f"http://127.0.0.1:{server.server_address[1]}"


def figures(page):
    text = page.eval_on_selector("#strands-figures", "e => e.textContent")
    return json.loads(text) if text else None


def wait_for(page, condition, timeout, what, every=None):
    """Poll the figures until `condition` holds; `every` sees each reading."""
    deadline = time.monotonic() + timeout
    last = None
    while time.monotonic() < deadline:
        last = figures(page)
        if last is not None:
            if every:
                every(last)
            if condition(last):
                return last
        page.wait_for_timeout(250)
    raise Failure(f"timed out after {timeout:.0f} s waiting for {what}; last figures: {last}")


def decode_png(data):
    """Width, height, channels and the raw pixel bytes of an 8-bit non-interlaced PNG."""
    check(data[:8] == b"\x89PNG\r\n\x1a\n", "the screenshot is not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    check(depth == 8 and colour in (2, 6) and interlace == 0, f"unexpected PNG format {header}")
    channels = 3 if colour == 2 else 4
    raw, stride = zlib.decompress(idat), width * channels
    pixels, previous = bytearray(), bytearray(stride)
    for y in range(height):
        line = raw[y * (stride + 1) : (y + 1) * (stride + 1)]
        kind, row = line[0], bytearray(line[1:])
        for i in range(stride):
            a = row[i - channels] if i >= channels else 0
            b = previous[i]
            c = previous[i - channels] if i >= channels else 0
            if kind == 1:
                row[i] = (row[i] + a) & 255
            elif kind == 2:
                row[i] = (row[i] + b) & 255
            elif kind == 3:
                row[i] = (row[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                row[i] = (row[i] + pred) & 255
        pixels += row
        previous = row
    return width, height, channels, bytes(pixels)


def drawn(png):
    """Distinct colours, and the share of pixels unlike the most common one."""
    width, height, channels, pixels = decode_png(png)
    counts = {}
    for i in range(0, len(pixels), channels * 7):  # every 7th pixel is plenty
        colour = pixels[i : i + 3]
        counts[colour] = counts.get(colour, 0) + 1
    total = sum(counts.values())
    return len(counts), 1.0 - max(counts.values()) / total


def check_frames(page, out, name):
    png = page.locator("#strands").screenshot()
    (out / f"browser_{name}.png").write_bytes(png)
    colours, share = drawn(png)
    # The canvas holds the scene alone (the panel is the page's HTML): the box's outline
    # is a third of a percent of it, a blank canvas one colour.
    check(colours >= 20 and share >= 0.01,
          f"{name}: the canvas looks blank ({colours} colours, {share:.1%} not background)")
    return colours, share


def check_exact(f, name):
    check(f["finite"], f"{name}: a non-finite figure: {f}")
    check(f["max_rel_length_error"] <= ERROR_BOUND,
          f"{name}: max relative length error {f['max_rel_length_error']:.3e} > {ERROR_BOUND}")
    check(f["edge_crossings"] in (None, 0), f"{name}: {f['edge_crossings']} crossed step ends")


def report(name, f, colours, share):
    rate = f["real_time_factor"]
    print(f"{name}: {f['time']:.2f} s simulated in {f['steps']} steps, {f['frames']} frames, "
          f"{f['particles']} particles, max_rel_length_error {f['max_rel_length_error']:.2e}, "
          f"crossings {f['edge_crossings']}, real-time factor "
          f"{'not measured' if rate is None else f'{rate:.2f}'}; "
          f"screenshot {colours} colours, {share:.1%} drawn", flush=True)


def factory(page, url, out, scene, seconds):
    opened = time.monotonic()
    page.goto(f"{url}/?scene={scene}")
    wait_for(page, lambda f: f["scene"] == scene and f["frames"] >= 1, LOAD_TIMEOUT,
             f"{scene}'s first frame")
    # Measured, not asserted: how long a visitor waits for a picture (the wasm fetched,
    # compiled and started; the first page of a browser session is the cold one).
    print(f"{scene}: first frame drawn {time.monotonic() - opened:.1f} s after the page "
          f"was opened", flush=True)
    wait_for(page, lambda f: f["scene"] == scene and f["steps"] > 0, LOAD_TIMEOUT,
             f"{scene} to start")
    counts = []
    f = wait_for(page, lambda f: f["time"] >= seconds, RUN_TIMEOUT,
                 f"{scene} to reach {seconds} simulated seconds",
                 every=lambda f: counts.append(f["particles"]))
    check_exact(f, scene)
    check(counts[-1] > counts[0],
          f"{scene}: the particle count did not grow ({counts[0]} -> {counts[-1]})")
    check(f["frames"] >= 10, f"{scene}: only {f['frames']} frames drawn")
    report(scene, f, *check_frames(page, out, scene))
    page.wait_for_timeout(300)  # the footer's figures refresh four times a second
    page.screenshot(path=str(out / f"page_{scene}.png"))


def to_page(a, b):
    """The pixel of a world point, from two (pixel, world) pairs (uniform scale, y up)."""
    (pa, wa), (pb, wb) = a, b
    scale = (pb[0] - pa[0]) / (wb[0] - wa[0])
    return lambda x, y: (pa[0] + (x - wa[0]) * scale, pa[1] - (y - wa[1]) * scale)


def cursor_at(page, x, y):
    page.mouse.move(x, y)
    f = wait_for(page, lambda f: f["cursor"] is not None and f["frames"] > 0, 30,
                 f"the cursor at ({x}, {y}) to be read")
    page.wait_for_timeout(300)  # a frame for the new position to be seen
    return figures(page)


def rope(page, url, out):
    scene = "long_strand"
    page.goto(f"{url}/?scene={scene}")
    wait_for(page, lambda f: f["scene"] == scene and f["steps"] > 0, LOAD_TIMEOUT,
             "the rope to start")
    # Let it land and settle on the floor.
    wait_for(page, lambda f: f["time"] >= 2.5, RUN_TIMEOUT, "the rope to settle")
    # Where the world is on the page, from the pointer's world position at two pixels.
    a = ((200.0, 200.0), cursor_at(page, 200, 200)["cursor"])
    b = ((500.0, 500.0), cursor_at(page, 500, 500)["cursor"])
    pixel = to_page(a, b)
    # Sweep along the floor, where the strand lies, until a particle is under the pointer.
    grabbed = None
    for i in range(60):
        x, y = pixel(0.3 + 0.01 * i, 0.008)
        page.mouse.move(x, y)
        page.wait_for_timeout(60)
        f = figures(page)
        if f["hovering"]:
            grabbed = (x, y)
            break
    check(grabbed is not None, "no particle of the rope found on the floor")
    x, y = grabbed
    page.mouse.down()
    # Frames come slowly in software WebGL: let one see the press before moving.
    wait_for(page, lambda f: f["dragging"], 30, "the press to grab the particle")
    lifted = []
    for step in range(1, 16):
        page.mouse.move(x, y - 20 * step)
        page.wait_for_timeout(100)
        lifted.append(figures(page)["dragging"])
    page.wait_for_timeout(800)
    mid = figures(page)
    colours, share = check_frames(page, out, "rope_dragged")
    page.mouse.up()
    check(all(lifted) and mid["dragging"], f"the drag did not hold the particle: {lifted}")
    f = wait_for(page, lambda f: not f["dragging"], 30, "the drag to end")
    page.wait_for_timeout(1000)
    f = figures(page)
    check_exact(f, "rope")
    report("rope (dragged 300 px up and let go)", f, colours, share)


def panel(page, url):
    """The page's HTML panel drives the simulation through its commands."""
    page.goto(f"{url}/?scene=long_strand")
    wait_for(page, lambda f: f["steps"] > 0 and f["frames"] >= 2, LOAD_TIMEOUT,
             "the rope to start")
    page.click("#pause")
    paused = wait_for(page, lambda f: f["paused"], 30, "the pause button to pause")
    page.wait_for_timeout(1000)
    still = figures(page)
    check(still["steps"] == paused["steps"] and still["time"] == paused["time"],
          f"the clock ran while paused: {paused['steps']} -> {still['steps']} steps")
    check(page.inner_text("#pause").endswith("run"), "the pause button does not offer to run")
    page.click("button[data-command=step]")
    stepped = wait_for(page, lambda f: f["steps"] > still["steps"], 30, "a step")
    check(stepped["steps"] == still["steps"] + still["substeps"] and stepped["paused"],
          f"step took {stepped['steps'] - still['steps']} steps, not one tick of "
          f"{still['substeps']}, or ran on")
    page.select_option("#dt", "0.016666666666666666")
    page.fill("#substeps", "2")
    page.dispatch_event("#substeps", "change")
    page.click("button[data-tool=pin]")
    f = wait_for(page, lambda f: f["tool"] == "pin" and f["substeps"] == 2
                 and abs(f["dt"] - 1 / 60) < 1e-12, 30, "dt, substeps and tool to be set")
    page.wait_for_timeout(300)
    check(page.get_attribute("button[data-tool=pin]", "aria-pressed") == "true",
          "the pin tool's button is not shown pressed")
    # A bad command (as a script on the page might send) is refused and said why.
    page.eval_on_selector("#strands-commands", "e => e.textContent += 'dt 7\\n'")
    wait_for(page, lambda f: f["message"] is not None and "outside" in f["message"], 30,
             "the bad command's reason")
    page.wait_for_timeout(300)
    check("outside" in page.inner_text("#message"), "the panel does not show the refusal")
    check(abs(figures(page)["dt"] - 1 / 60) < 1e-12, "a refused dt changed the step")
    page.click("#pause")
    ran = wait_for(page, lambda f: not f["paused"] and f["steps"] > stepped["steps"] + 4, 60,
                   "run to start the clock again")
    check_exact(ran, "the rope at 1/60 s")
    page.select_option("#scene", "meatball_factory")
    f = wait_for(page, lambda f: f["scene"] == "meatball_factory" and f["steps"] > 0, 60,
                 "the scene menu to switch to the meatball factory")
    check("scene=meatball_factory" in page.url, f"the address was not updated: {page.url}")
    check_exact(f, "meatball_factory after the switch")
    print(f"panel: paused at {paused['steps']} steps, one tick of {still['substeps']} steps "
          f"taken, dt 1/60 s with 2 substeps and the pin tool set, 'dt 7' refused "
          f"({f['message'] or 'cleared'}), run to {ran['steps']} steps, switched to "
          f"{f['scene']} in place", flush=True)


def bad_scene(page, url, console):
    """An unknown scene in the address: the first scene shown, and the console says why."""
    console.clear()
    page.goto(f"{url}/?scene=no_such_scene")
    f = wait_for(page, lambda f: f["steps"] > 0, LOAD_TIMEOUT, "the page to start")
    check(f["scene"] == "spaghetti_factory", f"showing {f['scene']}, not the first scene")
    said = [m for m in console if "no_such_scene" in m]
    check(said, f"no console message names the unknown scene; the last ones: {console[-5:]}")
    print(f"unknown scene: the spaghetti factory shown; the console says {said[0]!r}",
          flush=True)


def main():
    folder = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "target/web-demo")
    check((folder / "index.html").exists() and (folder / "strands_bg.wasm").exists(),
          f"{folder} holds no built demo: run scripts/web.sh first")
    server, url = serve(folder)
    errors = []
    try:
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=CHROMIUM, headless=True,
                                                 args=CHROMIUM_ARGS)
            page = browser.new_page(viewport=VIEWPORT)
            page.on("pageerror", lambda e: errors.append(str(e)))
            console = []
            page.on("console", lambda m: console.append(m.text))
            factory(page, url, folder, "spaghetti_factory", 3.0)
            factory(page, url, folder, "meatball_factory", 3.0)
            rope(page, url, folder)
            panel(page, url)
            bad_scene(page, url, console)
            browser.close()
    finally:
        server.shutdown()
    # winit leaves its start-up by throwing; anything else is a failure.
    real = [e for e in errors if "Using exceptions for control flow" not in e]
    check(not real, f"errors in the page: {real}")
    print(f"browser test passed; screenshots in {folder}")


if __name__ == "__main__":
    try:
        main()
    except Failure as failure:
        print(f"browser test FAILED: {failure}", file=sys.stderr)
        sys.exit(1)
