#!/usr/bin/env python3
"""Browser test of the survey: one participant's whole session in headless Chromium.

Opens the survey, gives consent, answers every question by clicking (reloading once midway to
check that the session resumes), finishes, reloads again (finishing is idempotent). Then checks
blinding on the wire: every response body the browser received (HTML, JS, CSS, JSON, GIFs,
captured through the DevTools protocol) and the session JSON fetched again with urllib under the
same token are searched for the run's configuration ids, variable values and mesh file names.
Saves a screenshot of one question screen. With --record FILE, writes what the participant saw
and did: per answered question its position, the two animation names on the screen (left,
right) and the side clicked, so that the export can be checked against the screen.

Needs Debian's chromium, chromium-driver and python3-selenium (nothing is downloaded):
    /usr/bin/python3 survey_browser.py --url http://127.0.0.1:PORT/ --run RUN --screenshot q.png
Prints one JSON line with the session token and the number of answers.
"""

import argparse
import base64
import csv
import json
import os
import re
import sys
import tempfile
import urllib.request

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

CHOICES = ["L", "N", "R"]


def secrets(run, columns=None):
    """Words that would reveal a configuration: ids, variable values and mesh file names.

    By default every column of configurations.csv but id and name is a variable, and the column
    names are secret too. With `columns`, only those columns' values are (a run folder of
    `experiments run` also has numeric columns and generic names such as `method`).
    """
    words = set()
    with open(os.path.join(run, "key.csv"), newline="") as f:
        for row in csv.DictReader(f):
            words.add(row["id"])
            words.add(row["id"] + ".ply")
    with open(os.path.join(run, "configurations.csv"), newline="") as f:
        reader = csv.DictReader(f)
        if columns is not None:
            missing = [c for c in columns if c not in reader.fieldnames]
            assert not missing, f"configurations.csv has no column {missing}"
        for row in reader:
            for column, value in row.items():
                if column in ("id", "name") or not value:
                    continue
                if columns is None or column in columns:
                    words.add(value)
        if columns is None:
            words.update(c for c in reader.fieldnames if c not in ("id", "name"))
    words.add("key.csv")
    return sorted(w for w in words if w)


def leaks(body, words):
    """The secret words found in a body (whole words, case-insensitive)."""
    found = []
    lower = body.lower()
    for w in words:
        # The substring test first: the regular expression is slow on megabytes of GIF.
        if w.lower() in lower and re.search(r"(?<![a-z0-9_])" + re.escape(w.lower()) + r"(?![a-z0-9_])", lower):
            found.append(w)
    return found


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--url", required=True)
    ap.add_argument("--run", required=True)
    ap.add_argument("--screenshot", required=True)
    ap.add_argument("--chromedriver", default="/usr/bin/chromedriver")
    ap.add_argument("--chromium", default="/usr/bin/chromium")
    ap.add_argument("--record", help="write the screens and clicks as JSON to this file")
    ap.add_argument(
        "--secret-columns",
        help="comma-separated columns of configurations.csv whose values are secret (default:"
        " every column but id and name, and the column names); binary bodies (the GIFs) are"
        " then searched for the words of at least 3 characters only",
    )
    args = ap.parse_args()
    url = args.url if args.url.endswith("/") else args.url + "/"

    profile = tempfile.mkdtemp(prefix="survey-chromium-")
    opts = Options()
    opts.binary_location = args.chromium
    for flag in [
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--window-size=1280,900",
        "--user-data-dir=" + profile,
    ]:
        opts.add_argument(flag)
    opts.set_capability("goog:loggingPrefs", {"performance": "ALL"})
    driver = webdriver.Chrome(service=Service(args.chromedriver), options=opts)
    bodies = {}  # url -> text of every response body seen

    def collect():
        """Reads the response bodies of the requests logged since the last call."""
        for entry in driver.get_log("performance"):
            msg = json.loads(entry["message"])["message"]
            if msg.get("method") != "Network.loadingFinished":
                continue
            rid = msg["params"]["requestId"]
            try:
                got = driver.execute_cdp_cmd("Network.getResponseBody", {"requestId": rid})
            except Exception:
                continue  # redirects, cached entries without a body
            body = got["body"]
            binary = bool(got.get("base64Encoded"))
            if binary:
                body = base64.b64decode(body).decode("latin-1")
            bodies[rid] = (body, binary)

    try:
        driver.execute_cdp_cmd("Network.enable", {})
        driver.execute_cdp_cmd(
            "Emulation.setDeviceMetricsOverride",
            {"width": 1280, "height": 900, "deviceScaleFactor": 1, "mobile": False},
        )
        wait = WebDriverWait(driver, 30)
        driver.get(url)
        wait.until(lambda d: d.find_element(By.ID, "intro").is_displayed())
        driver.find_element(By.ID, "consent-check").click()
        driver.find_element(By.ID, "start").click()

        def progress():
            return driver.find_element(By.ID, "progress-text").text

        wait.until(lambda d: d.find_element(By.ID, "question").is_displayed())
        m = re.match(r"Question (\d+) of (\d+)", progress())
        assert m, progress()
        total = int(m.group(2))
        answered = 0
        record = []
        reloaded = False
        shot = False
        while True:
            if driver.find_element(By.ID, "done").is_displayed():
                break
            number = answered + 1
            wait.until(lambda d: progress() == f"Question {number} of {total}")
            # Both animations loaded and upscaled x2 with nearest-neighbour sampling.
            wait.until(
                lambda d: d.execute_script(
                    "const l = document.getElementById('left'), r = document.getElementById('right');"
                    "return l.complete && r.complete && l.naturalWidth > 0 && r.naturalWidth > 0"
                    " && l.clientWidth === 2 * l.naturalWidth && r.clientWidth === 2 * r.naturalWidth;"
                )
            )
            rendering = driver.execute_script(
                "return getComputedStyle(document.getElementById('left')).imageRendering;"
            )
            assert rendering == "pixelated", rendering
            if number == 3 and not shot:
                driver.save_screenshot(args.screenshot)
                shot = True
            if number == total // 2 + 1 and not reloaded:
                # A reload resumes at the first unanswered question.
                collect()
                driver.refresh()
                reloaded = True
                wait.until(lambda d: d.find_element(By.ID, "question").is_displayed())
                continue
            code = CHOICES[number % 3]
            left, right = driver.execute_script(
                "return ['left', 'right'].map(s => decodeURIComponent("
                "document.getElementById(s).getAttribute('src').split('/').pop()"
                ".replace(/\\.gif$/, '')));"
            )
            record.append({"position": number, "left": left, "right": right, "clicked": code})
            driver.find_element(By.CSS_SELECTOR, f'.choice[data-answer="{code}"]').click()
            answered += 1
            wait.until(
                lambda d: d.find_element(By.ID, "done").is_displayed()
                or progress() == f"Question {answered + 1} of {total}"
            )
        assert answered == total, (answered, total)
        if args.record:
            with open(args.record, "w") as f:
                json.dump(record, f, indent=1)
        assert reloaded and shot
        # Finished; a reload shows the end again (finishing is idempotent).
        collect()
        driver.refresh()
        wait.until(lambda d: d.find_element(By.ID, "done").is_displayed())
        token = driver.execute_script("return localStorage.getItem('rmt-survey-token');")
        collect()

        # The session as the participant's token can fetch it, outside the browser too.
        req = urllib.request.Request(
            url + "api/session", headers={"Authorization": "Bearer " + token}
        )
        with urllib.request.urlopen(req) as resp:
            session = resp.read().decode()
        view = json.loads(session)
        assert view["finished"] is True and len(view["answers"]) == total, view
        bodies["urllib:/api/session"] = (session, False)

        columns = args.secret_columns.split(",") if args.secret_columns else None
        words = secrets(args.run, columns)
        # Two random bytes of a GIF often read as a short word between non-letters.
        binary_words = words if columns is None else [w for w in words if len(w) >= 3]
        assert len(bodies) >= 6, f"only {len(bodies)} bodies captured"
        leaked = {
            rid: leaks(body, binary_words if binary else words)
            for rid, (body, binary) in bodies.items()
        }
        leaked = {k: v for k, v in leaked.items() if v}
        assert not leaked, f"blinding broken: {leaked}"
        print(
            json.dumps(
                {
                    "token": token,
                    "answers": total,
                    "bodies_checked": len(bodies),
                    "secrets_searched": len(words),
                    "screenshot": args.screenshot,
                }
            )
        )
    finally:
        driver.quit()


if __name__ == "__main__":
    sys.exit(main())
