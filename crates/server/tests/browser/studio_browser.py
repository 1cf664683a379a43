#!/usr/bin/env python3
"""Browser test of the studio in headless Chromium (software WebGL2 through SwiftShader).

Loads the studio, waits for the first mesh, checks that the canvas is not blank (a clear share of
its pixels differs from the background, read from a screenshot), changes the clustering and checks
that the triangle counter changes, measures the time from a parameter change to the updated frame
at 64^3 and the bytes per mesh, opens compare mode (blind), then sculpt mode: one stroke, checks
that the counter and the latency readout update, undo; LOD mode: the multiresolution world
with more than one level, W held to fly forward (the page asks the server for a re-mesh as the
camera moves), colour by level (the mesh's colours change), one stroke, then a new world with
clustering integrated at the same starting viewer (the same chunks per level, fewer triangles);
exports a .glb and loads it back (glTF 2.0
structure: header, JSON and BIN chunks, accessors within the buffer, indices within the vertices,
triangle count equal to the page's). Saves screenshots.

Needs Debian's chromium, chromium-driver and python3-selenium (nothing is downloaded):
    /usr/bin/python3 studio_browser.py --url http://127.0.0.1:PORT/studio/ --out DIR
Prints one JSON line of measurements.
"""

import argparse
import io
import json
import os
import statistics
import struct
import sys
import tempfile
import time
import urllib.request

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.support.ui import Select, WebDriverWait

BACKGROUND = (0xE9, 0xEC, 0xF1)


def fail(message):
    print(f"studio browser test FAILED: {message}", file=sys.stderr)
    sys.exit(1)


def png_pixels(png):
    """Decodes an 8-bit RGB/RGBA non-interlaced PNG (what Chromium writes) with zlib only."""
    import zlib

    assert png[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    at, idat, width, height, ctype = 8, b"", 0, 0, 0
    while at < len(png):
        n = struct.unpack(">I", png[at:at + 4])[0]
        kind = png[at + 4:at + 8]
        data = png[at + 8:at + 8 + n]
        if kind == b"IHDR":
            width, height, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", data)
            assert depth == 8 and ctype in (2, 6) and interlace == 0, "unexpected PNG layout"
        elif kind == b"IDAT":
            idat += data
        at += 12 + n
    raw = zlib.decompress(idat)
    bpp = 4 if ctype == 6 else 3
    stride = width * bpp
    rows, prev, at = [], bytearray(stride), 0
    for _ in range(height):
        f = raw[at]
        line = bytearray(raw[at + 1:at + 1 + stride])
        at += 1 + stride
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, bpp, rows


def share_not_background(png, box):
    """Share of pixels inside box (x0, y0, x1, y1) that differ clearly from the background."""
    width, height, bpp, rows = png_pixels(png)
    x0, y0, x1, y1 = [int(v) for v in box]
    x1, y1 = min(x1, width), min(y1, height)
    total = differ = 0
    for y in range(y0, y1, 2):
        row = rows[y]
        for x in range(x0, x1, 2):
            r, g, b = row[bpp * x], row[bpp * x + 1], row[bpp * x + 2]
            total += 1
            if abs(r - BACKGROUND[0]) + abs(g - BACKGROUND[1]) + abs(b - BACKGROUND[2]) > 30:
                differ += 1
    return differ / max(total, 1)


def mean_colour(png, box):
    """Mean RGB of the pixels inside box that differ clearly from the background (the mesh)."""
    width, height, bpp, rows = png_pixels(png)
    x0, y0, x1, y1 = [int(v) for v in box]
    x1, y1 = min(x1, width), min(y1, height)
    total, acc = 0, [0, 0, 0]
    for y in range(y0, y1, 2):
        row = rows[y]
        for x in range(x0, x1, 2):
            px = row[bpp * x], row[bpp * x + 1], row[bpp * x + 2]
            if sum(abs(px[i] - BACKGROUND[i]) for i in range(3)) > 30:
                total += 1
                for i in range(3):
                    acc[i] += px[i]
    return [a / max(total, 1) for a in acc]


def check_glb(data, triangles):
    """glTF 2.0 binary structure: returns (vertices, triangles)."""
    magic, version, length = struct.unpack("<III", data[:12])
    if magic != 0x46546C67 or version != 2 or length != len(data):
        fail(f"not a glTF 2.0 binary (magic {magic:#x}, version {version}, length {length}/{len(data)})")
    jlen, jtype = struct.unpack("<II", data[12:20])
    if jtype != 0x4E4F534A:
        fail("first chunk is not JSON")
    gltf = json.loads(data[20:20 + jlen])
    at = 20 + jlen
    blen, btype = struct.unpack("<II", data[at:at + 8])
    if btype != 0x004E4942:
        fail("second chunk is not BIN")
    binary = data[at + 8:at + 8 + blen]
    if gltf["asset"]["version"] != "2.0":
        fail("asset.version is not 2.0")
    prim = gltf["meshes"][0]["primitives"][0]
    acc = gltf["accessors"]
    views = gltf["bufferViews"]
    for a in acc:
        v = views[a["bufferView"]]
        if v.get("byteOffset", 0) + v["byteLength"] > len(binary):
            fail("a buffer view runs past the BIN chunk")
    pos = acc[prim["attributes"]["POSITION"]]
    idx = acc[prim["indices"]]
    if idx["count"] != 3 * triangles:
        fail(f"glb has {idx['count'] // 3} triangles, the page shows {triangles}")
    view = views[idx["bufferView"]]
    off = view.get("byteOffset", 0) + idx.get("byteOffset", 0)
    fmt = {5125: "I", 5123: "H"}[idx["componentType"]]
    size = struct.calcsize(fmt)
    indices = struct.unpack(f"<{idx['count']}{fmt}", binary[off:off + size * idx["count"]])
    if max(indices) >= pos["count"]:
        fail("glb index past the vertices")
    if not ("min" in pos and "max" in pos):
        fail("POSITION accessor lacks min/max (required by glTF)")
    return pos["count"], idx["count"] // 3


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--url", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--readme-shot", default=None, help="also save the object view here (docs/studio.png)")
    ap.add_argument("--chromedriver", default="/usr/bin/chromedriver")
    ap.add_argument("--chromium", default="/usr/bin/chromium")
    ap.add_argument("--repeats", type=int, default=5, help="parameter changes timed at 64^3")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    url = args.url if args.url.endswith("/") else args.url + "/"
    origin = url.split("/studio/")[0]

    profile = tempfile.mkdtemp(prefix="studio-chromium-")
    opts = Options()
    opts.binary_location = args.chromium
    for flag in [
        "--headless=new",
        "--no-sandbox",
        "--enable-unsafe-swiftshader",
        "--disable-gpu-sandbox",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--disable-dev-shm-usage",
        f"--user-data-dir={profile}",
        "--window-size=1280,800",
    ]:
        opts.add_argument(flag)
    driver = webdriver.Chrome(service=Service(args.chromedriver), options=opts)
    result = {}
    try:
        driver.execute_cdp_cmd(
            "Emulation.setDeviceMetricsOverride",
            {"width": 1280, "height": 760, "deviceScaleFactor": 1, "mobile": False},
        )
        wait = WebDriverWait(driver, 120, poll_frequency=0.1)
        state = lambda key: driver.execute_script(f"return window.studio && window.studio.{key}")
        driver.get(url)
        wait.until(lambda d: state("ready"))
        err = state("error")
        if err:
            fail(f"error shown after load: {err}")
        webgl2 = driver.execute_script(
            "return !!document.getElementById('view3d').getContext('webgl2')"
        )
        result["webgl2"] = bool(webgl2)

        def canvas_box():
            r = driver.execute_script(
                "const r = document.getElementById('view3d').getBoundingClientRect();"
                "return [r.left, r.top, r.right, r.bottom];"
            )
            return r

        def shot(name):
            png = driver.get_screenshot_as_png()
            with open(os.path.join(args.out, name), "wb") as f:
                f.write(png)
            return png

        def set_field(panel, name, value):
            el = driver.find_element(By.CSS_SELECTOR, f"#{panel} [name={name}]")
            if el.tag_name == "select":
                Select(el).select_by_value(value)
            else:
                el.clear()
                el.send_keys(value)

        def changed_mesh(action):
            before = state("meshes")
            action()
            wait.until(lambda d: state("meshes") > before and state("busy") == 0)
            if state("error"):
                fail(f"error shown: {state('error')}")

        # A 64^3 sphere: the first frame, not blank.
        changed_mesh(lambda: set_field("config-a", "resolution", "64"))
        png = shot("studio-object.png")
        share = share_not_background(png, canvas_box())
        result["object_nonbackground_share"] = round(share, 3)
        if share < 0.05:
            fail(f"canvas looks blank: only {share:.1%} of its pixels differ from the background")
        triangles_integrated = state("triangles[0]")

        # A bad parameter shows the command line's message in the page, and the mesh stays.
        shown_before = state("meshes")
        set_field("config-a", "resolution", "100000")
        wait.until(lambda d: state("error") and state("busy") == 0)
        message = driver.find_element(By.ID, "error").text
        result["error_message"] = message
        if "resolution" not in message and "too large" not in message:
            fail(f"the error shown does not name the parameter: {message!r}")
        if state("meshes") != shown_before:
            fail("a refused request replaced the mesh")
        changed_mesh(lambda: set_field("config-a", "resolution", "64"))
        if state("error"):
            fail(f"the error stayed after a good request: {state('error')}")

        # Clustering changes the triangle counter.
        changed_mesh(lambda: set_field("config-a", "clustering", "none"))
        triangles_none = state("triangles[0]")
        if triangles_none == triangles_integrated:
            fail(f"triangle counter did not change with clustering ({triangles_none})")
        result["triangles_integrated"] = triangles_integrated
        result["triangles_none"] = triangles_none
        overlay = driver.find_element(By.ID, "overlay-a").text
        if str(triangles_none) not in overlay:
            fail(f"overlay does not show the triangle count {triangles_none}: {overlay!r}")

        # Time from a parameter change to the updated frame at 64^3 (and bytes per mesh): the
        # page measures from its request to the frame after the new mesh; alternate clustering.
        times, sizes = [], []
        for i in range(args.repeats):
            changed_mesh(lambda: set_field("config-a", "clustering", "integrated" if i % 2 == 0 else "none"))
            times.append(state("lastUpdateMs"))
            sizes.append(state("lastBytes"))
        result["update_ms_median_64"] = round(statistics.median(times), 1)
        result["update_ms_all_64"] = [round(t, 1) for t in times]
        result["bytes_per_mesh_64"] = sorted(set(sizes))
        set_field("config-a", "clustering", "integrated")
        wait.until(lambda d: state("busy") == 0)
        time.sleep(0.5)
        wait.until(lambda d: state("busy") == 0)

        # Export the shown mesh as .glb and load it back.
        link = driver.find_element(By.CSS_SELECTOR, "#export-links a[data-format=glb]")
        href = link.get_attribute("href")
        data = urllib.request.urlopen(href, timeout=120).read()
        with open(os.path.join(args.out, "studio-export.glb"), "wb") as f:
            f.write(data)
        shown = state("triangles[0]")
        vertices, triangles = check_glb(data, shown)
        result["glb_bytes"] = len(data)
        result["glb_triangles"] = triangles
        result["glb_vertices"] = vertices

        # Colour by radius ratio, smooth shading: a screenshot for the README.
        driver.find_element(By.ID, "colour-ratio").click()
        wait.until(lambda d: state("busy") == 0 and not state("error"))
        time.sleep(1.0)
        wait.until(lambda d: state("busy") == 0)
        png = shot("studio-ratio.png")
        if args.readme_shot:
            with open(args.readme_shot, "wb") as f:
                f.write(png)
        driver.find_element(By.ID, "colour-ratio").click()
        wait.until(lambda d: state("busy") == 0)

        # Compare mode, blind: two meshes, labels hidden.
        # Outside blind mode the two configurations have their own colours; in blind mode both
        # sides must look alike but for the meshes (a colour per configuration would name them).
        driver.find_element(By.CSS_SELECTOR, "#modes button[data-mode=compare]").click()
        wait.until(lambda d: state("triangles[1]") and state("busy") == 0)
        time.sleep(0.5)
        box = canvas_box()
        mid = (box[0] + box[2]) / 2
        png = shot("studio-compare.png")
        seen = [mean_colour(png, (box[0], box[1], mid, box[3])), mean_colour(png, (mid, box[1], box[2], box[3]))]
        labelled_gap = sum(abs(a - b) for a, b in zip(*seen))
        driver.find_element(By.ID, "blind").click()
        time.sleep(0.5)
        png = shot("studio-compare-blind.png")
        seen = [mean_colour(png, (box[0], box[1], mid, box[3])), mean_colour(png, (mid, box[1], box[2], box[3]))]
        blind_gap = sum(abs(a - b) for a, b in zip(*seen))
        result["compare_colour_gap"] = {"labelled": round(labelled_gap, 1), "blind": round(blind_gap, 1)}
        if labelled_gap < 30:
            fail(f"compare mode: the two configurations are not told apart by colour ({labelled_gap:.1f})")
        if blind_gap > 12:
            fail(f"blind mode: the sides differ in colour ({blind_gap:.1f}), which names them")
        left = share_not_background(png, (box[0], box[1], mid, box[3]))
        right = share_not_background(png, (mid, box[1], box[2], box[3]))
        result["compare_shares"] = [round(left, 3), round(right, 3)]
        if left < 0.03 or right < 0.03:
            fail(f"compare mode: a side looks blank ({left:.1%}, {right:.1%})")
        overlays = driver.find_element(By.ID, "overlay-a").text + driver.find_element(By.ID, "overlay-b").text
        if "integrated" in overlays or "none" in overlays:
            fail(f"blind mode shows configuration labels: {overlays!r}")
        driver.find_element(By.ID, "blind").click()

        # Sculpt: one stroke at the canvas centre (where the terrain is), counter and latency.
        driver.find_element(By.CSS_SELECTOR, "#modes button[data-mode=sculpt]").click()
        wait.until(lambda d: state("sculptTriangles") and state("busy") == 0)
        shot("studio-sculpt-before.png")
        before_tris = state("sculptTriangles")
        canvas = driver.find_element(By.ID, "view3d")
        latencies = []
        for k in range(5):
            edits = state("edits")
            ActionChains(driver).move_to_element_with_offset(canvas, 20 * k - 40, 10).click().perform()
            wait.until(lambda d: state("edits") > edits and state("busy") == 0)
            if state("error"):
                fail(f"sculpt error: {state('error')}")
            latencies.append(state("lastEditMs"))
        after_tris = state("sculptTriangles")
        readout = driver.find_element(By.ID, "overlay-a").text
        if "last edit" not in readout or "re-meshed" not in readout:
            fail(f"sculpt readout lacks latency/chunks: {readout!r}")
        if after_tris == before_tris:
            fail(f"sculpting did not change the triangle counter ({after_tris})")
        result["sculpt_triangles"] = [before_tris, after_tris]
        result["edit_ms_median"] = round(statistics.median(latencies), 1)
        result["edit_ms_all"] = [round(t, 1) for t in latencies]
        result["edit_chunks_last"] = state("lastChunks")
        png = shot("studio-sculpt.png")
        edits = state("edits")
        driver.find_element(By.ID, "undo").click()
        wait.until(lambda d: state("edits") > edits and state("busy") == 0)
        result["after_undo_triangles"] = state("sculptTriangles")

        # LOD: a fly camera over the multiresolution world, levels coloured, a stroke.
        driver.find_element(By.CSS_SELECTOR, "#modes button[data-mode=lod]").click()
        wait.until(lambda d: (state("lod.chunks") or 0) > 0 and state("busy") == 0)
        if state("error"):
            fail(f"LOD error: {state('error')}")
        levels = state("lod.levels")
        result["lod_chunks_per_level"] = levels
        lod_triangles_plain = state("lod.triangles")
        if sum(1 for n in levels if n > 0) < 2:
            fail(f"the LOD world shows one level only: {levels}")
        png = shot("studio-lod.png")
        box = canvas_box()
        share = share_not_background(png, box)
        result["lod_nonbackground_share"] = round(share, 3)
        if share < 0.05:
            fail(f"LOD view looks blank ({share:.1%})")
        plain = mean_colour(png, box)
        start = state("lod.viewer")
        moves = state("lod.moves")
        ActionChains(driver).key_down("w").pause(3.0).key_up("w").perform()
        wait.until(lambda d: state("lod.moves") > moves)
        time.sleep(1.0)
        wait.until(lambda d: state("busy") == 0)
        if state("error"):
            fail(f"LOD error after flying: {state('error')}")
        end = state("lod.viewer")
        flown = sum((a - b) ** 2 for a, b in zip(start, end)) ** 0.5
        result["lod_flown"] = round(flown, 3)
        result["lod_moves"] = state("lod.moves") - moves
        result["lod_move_ms_last"] = round(state("lod.lastMoveMs"), 1)
        if flown < 0.1:
            fail(f"holding W did not move the viewer the server meshes for ({start} -> {end})")
        driver.find_element(By.ID, "lod-colour").click()
        time.sleep(0.5)
        png = shot("studio-lod-levels.png")
        coloured = mean_colour(png, box)
        gap = sum(abs(a - b) for a, b in zip(plain, coloured))
        result["lod_level_colour_gap"] = round(gap, 1)
        if gap < 20:
            fail(f"colour by level did not change the view's colours ({gap:.1f})")
        if driver.find_element(By.ID, "lod-legend").get_attribute("hidden") is not None:
            fail("no level legend with colour by level")
        canvas = driver.find_element(By.ID, "view3d")
        # Above the centre: ground a few chunks away, usually coarser than where the camera is.
        ActionChains(driver).move_to_element_with_offset(canvas, 0, -120).click().perform()
        wait.until(lambda d: (state("lod.strokes") or 0) > 0 and state("busy") == 0)
        if state("error"):
            fail(f"LOD stroke error: {state('error')}")
        result["lod_stroke_ms"] = round(state("lod.lastStrokeMs"), 1)
        result["lod_stroke_status"] = driver.find_element(By.ID, "status").text
        shot("studio-lod-stroke.png")

        # Clustering at every level: a new world with clustering integrated starts at the same
        # viewer as the first (plain) one, so it has the same chunks per level and fewer
        # triangles, and the overlay shows the new count.
        worlds = state("lod.worlds")
        set_field("lod-config", "clustering", "integrated")
        driver.find_element(By.ID, "lod-new").click()
        wait.until(lambda d: state("lod.worlds") > worlds and state("busy") == 0)
        if state("error"):
            fail(f"LOD error with clustering: {state('error')}")
        clustered_levels = state("lod.levels")
        lod_triangles_clustered = state("lod.triangles")
        result["lod_triangles_plain"] = lod_triangles_plain
        result["lod_triangles_clustered"] = lod_triangles_clustered
        if clustered_levels != levels:
            fail(f"the clustered world has other chunks per level: {clustered_levels} vs {levels}")
        if not 0 < lod_triangles_clustered < lod_triangles_plain:
            fail(
                f"clustering did not lower the LOD triangle count: {lod_triangles_clustered} "
                f"vs {lod_triangles_plain} plain"
            )
        overlay = driver.find_element(By.ID, "overlay-a").text
        if str(lod_triangles_clustered) not in overlay:
            fail(f"overlay does not show the clustered count {lod_triangles_clustered}: {overlay!r}")
        png = shot("studio-lod-clustered.png")
        share = share_not_background(png, canvas_box())
        result["lod_clustered_nonbackground_share"] = round(share, 3)
        if share < 0.05:
            fail(f"clustered LOD view looks blank ({share:.1%})")
        print(json.dumps(result))
    finally:
        driver.quit()


if __name__ == "__main__":
    main()
