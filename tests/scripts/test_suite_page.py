#!/usr/bin/python3
"""A suite's web page (index.html) in a real browser: a small suite (the small cantilever and
cloth, three learned and linear methods and the full-space reference, plots, videos and the
error decomposition) is run with the CLI, and its page opened in headless Chromium through
chromedriver (Debian chromium, chromium-driver, python3-selenium). Asserts: no console
errors; every <img> and <video> resolves to a file that exists and loads; clicking a column
header reorders the rows (ascending, then descending); every method of the suite appears in
every scene's methods table; nothing is fetched from the network. Keeps a full-page
screenshot as a test artefact (--artefacts, default <tmp>/browser). Run by ctest (label
browser):

  /usr/bin/python3 tests/scripts/test_suite_page.py --cli build/latentbench --tmp build/tests/tmp

Exits 77 (ctest's SKIP_RETURN_CODE) with a message if chromium, chromedriver, selenium or
ffmpeg is missing.
"""
import base64
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

import script_test
import urllib.parse

SKIP = 77
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"

for path, package in ((CHROMIUM, "chromium"), (CHROMEDRIVER, "chromium-driver"), ("/usr/bin/ffmpeg", "ffmpeg")):
    if not os.path.exists(path):
        print(f"SKIPPED: {path} not installed (Debian package {package}; scripts/run setup installs it)")
        sys.exit(SKIP)
try:
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By
except ImportError:
    print("SKIPPED: selenium not importable (Debian package python3-selenium; scripts/run setup installs it)")
    sys.exit(SKIP)

METHODS = ["ours", "sup", "pca", "full_space"]  # the suite's integrators and the reference
SUITE = """
name = "page_test"
description = "The browser test's suite: small cantilever and cloth, <escaped> & \\"quoted\\""
[autoencoder]
hidden = [16]
pca = 8
epochs = 20
batch = 16
learning_rate = 1.0e-3
[training]
epochs = 5
hidden = [16]
learning_rate = 1.0e-3
[[integrators]]
name = "ours"
[[integrators]]
name = "sup"
loss = "supervised_l2"
[[integrators]]
name = "pca"
method = "linear_pca"
[[scenes]]
scene = "experiments/scenes/cantilever.toml"
variant = "small"
[[scenes]]
scene = "experiments/scenes/cloth.toml"
variant = "small"
[evaluation]
frames = 50
[outputs]
plots = true
videos = true
video_frames = 12
diagnose = true
diagnose_stride = 25
[[ablations]]
name = "supervision"
methods = ["ours", "sup"]
"""

ARGS = None


def run(argv):
    """Run a command (never through a shell); fail the test with its output if it fails."""
    p = subprocess.run(argv, capture_output=True, text=True, cwd=REPO)
    if p.returncode != 0:
        raise AssertionError(f"{' '.join(argv)} exited {p.returncode}:\n{p.stdout}\n{p.stderr}")
    return p.stdout


def file_of(url):
    """The local path of a file:// URL."""
    parsed = urllib.parse.urlparse(url)
    assert parsed.scheme == "file", url
    return urllib.parse.unquote(parsed.path)


class SuitePageTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        # The run folder stays in the build tree: a second ctest run reuses its stages (the
        # tables and the page are rewritten every run).
        cls.work = os.path.join(ARGS.tmp, "suite_page")
        os.makedirs(cls.work, exist_ok=True)
        cls.suite = os.path.join(cls.work, "suite.toml")
        with open(cls.suite, "w") as f:
            f.write(SUITE)
        cls.run_dir = os.path.join(cls.work, "run")
        cls.page = os.path.join(cls.run_dir, "index.html")
        if os.path.exists(cls.page):
            os.remove(cls.page)
        run([ARGS.cli, "-q", "run", cls.suite, "-o", cls.run_dir])
        assert os.path.exists(cls.page), "the run wrote no index.html"
        with open(cls.page, encoding="utf-8") as f:
            cls.html = f.read()

        cls.profile = tempfile.mkdtemp(prefix="chromium_profile_", dir=cls.work)
        options = Options()
        options.binary_location = CHROMIUM
        for a in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--disable-dev-shm-usage", "--autoplay-policy=no-user-gesture-required",
                  f"--user-data-dir={cls.profile}", "--window-size=1400,1000"):
            options.add_argument(a)
        options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
        cls.driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
        cls.driver.set_page_load_timeout(60)
        cls.driver.get("file://" + urllib.parse.quote(os.path.abspath(cls.page)))
        cls.wait_for_media()

    @classmethod
    def wait_for_media(cls):
        """Until every image finished loading and every video has its metadata (or 20 s)."""
        deadline = time.time() + 20
        while time.time() < deadline:
            done = cls.driver.execute_script(
                "return Array.from(document.images).every(i => i.complete) && "
                "Array.from(document.querySelectorAll('video')).every(v => v.readyState >= 1 || v.error);")
            if done:
                return
            time.sleep(0.2)

    @classmethod
    def tearDownClass(cls):
        driver = getattr(cls, "driver", None)
        if driver is not None:
            driver.quit()
        shutil.rmtree(getattr(cls, "profile", ""), ignore_errors=True)

    def test_page_command_rebuilds_the_page_and_a_listing(self):
        # `latentbench page` rewrites the page from the folder alone, and links it from a listing.
        listing = os.path.join(self.work, "index.html")
        out = run([ARGS.cli, "page", self.run_dir, "--listing", listing])
        self.assertIn(f"wrote {self.page}", out)
        with open(self.page, encoding="utf-8") as f:
            rebuilt = f.read()
        strip = lambda html: re.sub(r"Page written by latentbench on [^<]*", "", html)
        self.assertEqual(strip(rebuilt), strip(self.html), "the rebuilt page differs from the run's")
        self.driver.get("file://" + urllib.parse.quote(listing))
        links = self.driver.execute_script(
            "return Array.from(document.querySelectorAll('#suites a')).map(a => a.href);")
        self.assertIn("file://" + urllib.parse.quote(os.path.abspath(self.page)), links)
        self.assertEqual([e for e in self.driver.get_log("browser") if e["level"] == "SEVERE"], [])
        self.driver.get("file://" + urllib.parse.quote(os.path.abspath(self.page)))
        self.wait_for_media()
        # a folder that is not a suite's: exit 1, the folder named, nothing written
        empty = tempfile.mkdtemp(prefix="not_a_suite_", dir=self.work)
        p = subprocess.run([ARGS.cli, "page", empty], capture_output=True, text=True)
        self.assertEqual(p.returncode, 1, p.stderr)
        self.assertIn(empty, p.stderr)
        self.assertFalse(os.path.exists(os.path.join(empty, "index.html")))
        shutil.rmtree(empty)

    def test_zz_screenshot(self):
        """Last (tests run in name order): the page as a test artefact, from the top."""
        os.makedirs(ARGS.artefacts, exist_ok=True)
        shot = os.path.join(ARGS.artefacts, "suite_page.png")
        if os.path.exists(shot):
            os.remove(shot)
        self.driver.execute_script("window.scrollTo(0, 0)")
        # The whole page (up to 12,000 px) through the DevTools protocol, which renders beyond
        # the window; the window's view if that fails (a loaded machine can time it out).
        try:
            size = self.driver.execute_cdp_cmd("Page.getLayoutMetrics", {})["cssContentSize"]
            clip = {"x": 0, "y": 0, "width": 1400, "height": min(size["height"], 12000), "scale": 1}
            data = self.driver.execute_cdp_cmd("Page.captureScreenshot",
                                               {"format": "png", "captureBeyondViewport": True, "clip": clip})["data"]
            with open(shot, "wb") as f:
                f.write(base64.b64decode(data))
        except Exception as e:  # selenium's TimeoutException and WebDriverException alike
            print(f"full-page screenshot failed ({type(e).__name__}); taking the 1400x1000 view")
            self.driver.save_screenshot(shot)
        with open(shot, "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n", "the screenshot is not a PNG")
        self.assertGreater(os.path.getsize(shot), 10_000)
        print(f"screenshot: {shot}")

    def test_no_console_errors(self):
        errors = [e for e in self.driver.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
        self.assertEqual(errors, [], "console errors on the page")

    def test_self_contained(self):
        self.assertIsNone(re.search(r"""(?:src|href)\s*=\s*["'](?:https?:)?//""", self.html), "a network URL")
        self.assertNotIn("<link", self.html)
        self.assertNotIn("@import", self.html)
        self.assertNotIn("<script src", self.html)

    def test_images_resolve_to_existing_files(self):
        images = self.driver.execute_script(
            "return Array.from(document.images).map(i => [i.getAttribute('src'), i.currentSrc, i.naturalWidth]);")
        # the suite draws per scene a filmstrip and per-metric plots
        self.assertGreaterEqual(len(images), 4, images)
        for src, url, width in images:
            self.assertFalse(os.path.isabs(src), f"{src}: not a relative path")
            self.assertTrue(os.path.isfile(file_of(url)), f"<img src={src}>: {file_of(url)} does not exist")
            self.assertGreater(width, 0, f"<img src={src}> did not load")
        for scene in ("cantilever_small", "cloth_small"):
            self.assertIn(f"figures/{scene}_filmstrip.png", [s for s, _, _ in images])

    def test_videos_resolve_to_existing_files_and_play(self):
        videos = self.driver.execute_script(
            "return Array.from(document.querySelectorAll('video')).map(v => "
            "[v.getAttribute('src'), v.currentSrc, v.error ? v.error.code : null, v.readyState, v.videoWidth]);")
        self.assertEqual(sorted(s for s, *_ in videos), ["videos/cantilever_small.mp4", "videos/cloth_small.mp4"])
        for src, url, error, ready, width in videos:
            self.assertTrue(os.path.isfile(file_of(url)), f"<video src={src}>: {file_of(url)} does not exist")
            self.assertIsNone(error, f"<video src={src}>: media error {error}")
            self.assertGreaterEqual(ready, 1, f"<video src={src}>: no metadata loaded")
            self.assertGreater(width, 0, f"<video src={src}>: no video frame size")

    def rows(self, table_id):
        return self.driver.execute_script(
            "return Array.from(document.getElementById(arguments[0]).tBodies[0].rows).map(r => "
            "Array.from(r.cells).map(c => [c.textContent, c.getAttribute('data-v')]));", table_id)

    def test_every_method_in_every_scene(self):
        tables = self.driver.execute_script(
            "return Array.from(document.querySelectorAll('section.scene table[id^=table-methods-]')).map(t => t.id);")
        self.assertEqual(sorted(tables), ["table-methods-cantilever_small", "table-methods-cloth_small"])
        for table_id in tables:
            headers = [th.text for th in self.driver.find_elements(By.CSS_SELECTOR, f"#{table_id} thead th")]
            column = headers.index("method")
            shown = {row[column][0] for row in self.rows(table_id)}
            for m in METHODS:
                self.assertIn(m, shown, f"{table_id}: method {m} missing")
            # seeds per method, from the tidy observations table
            self.assertIn("seeds", headers)

    def test_clicking_a_header_sorts_the_rows(self):
        table_id = "table-methods-cloth_small"
        headers = self.driver.find_elements(By.CSS_SELECTOR, f"#{table_id} thead th")
        before = self.rows(table_id)

        def numbers(rows, c):
            return [float(r[c][1]) for r in rows if r[c][1] not in (None, "nan")]

        # a numeric column whose rows are not already in ascending order
        candidates = [c for c in range(len(headers))
                      if len(set(numbers(before, c))) >= 2 and numbers(before, c) != sorted(numbers(before, c))]
        self.assertTrue(candidates, "no numeric column out of order to sort")
        c = candidates[0]
        headers[c].click()
        ascending = self.rows(table_id)
        self.assertNotEqual(ascending, before, f"clicking '{headers[c].text}' did not reorder the rows")
        self.assertEqual(numbers(ascending, c), sorted(numbers(before, c)))
        self.assertEqual(sorted(map(str, ascending)), sorted(map(str, before)), "rows lost or changed")
        headers[c].click()
        descending = self.rows(table_id)
        self.assertEqual(numbers(descending, c), sorted(numbers(before, c), reverse=True))
        self.assertEqual(headers[c].get_attribute("aria-sort"), "descending")

    def test_sections_and_escaping(self):
        text = self.driver.find_element(By.TAG_NAME, "body").text
        for heading in ("Error decomposition", "Deviations from the paper's recipe", "Per-metric plots", "Provenance"):
            self.assertIn(heading, text)
        # the description's markup characters are shown as text, not parsed
        self.assertIn('<escaped> & "quoted"', text)
        self.assertIn("&lt;escaped&gt; &amp; &quot;quoted&quot;", self.html)
        for key in ("commit", "command", "machine", "date"):
            self.assertIn(key, text.lower())


def main():
    global ARGS
    ARGS, rest = script_test.arguments(extra=lambda parser: parser.add_argument(
        "--artefacts", help="where the screenshot goes (default: <tmp>/browser)"))
    ARGS.artefacts = os.path.abspath(ARGS.artefacts or os.path.join(ARGS.tmp, "browser"))
    return script_test.run(rest)


if __name__ == "__main__":
    sys.exit(main())
