#!/usr/bin/python3
"""scripts/plot_video.py on a small cloth (20 frames): ffprobe confirms the MP4's
codec (H.264, yuv420p), frame rate (30 fps), frame count and size (<= 1280 px
wide, even). Run by ctest (label unit):

  /usr/bin/python3 tests/scripts/test_plot_video.py --cli build/latentbench --tmp build/tests/tmp

Exits 77 (ctest's SKIP_RETURN_CODE) with a message if ffmpeg/ffprobe is not installed.
"""
import json
import os
import shutil
import subprocess
import sys
import unittest

import script_test

SKIP = 77
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
VIDEO = os.path.join(REPO, "scripts", "plot_video.py")
FRAMES = 20

FFPROBE = shutil.which("ffprobe")
if FFPROBE is None or shutil.which("ffmpeg") is None:
    print("SKIPPED: ffmpeg/ffprobe not installed (Debian package ffmpeg; scripts/run setup installs it)")
    sys.exit(SKIP)

import h5py  # noqa: E402
import numpy as np  # noqa: E402

ARGS = None


def run(argv):
    """Run a command (never through a shell); fail the test with its output if it fails."""
    p = subprocess.run(argv, capture_output=True, text=True)
    if p.returncode != 0:
        raise AssertionError(f"{' '.join(argv)} exited {p.returncode}:\n{p.stdout}\n{p.stderr}")
    return p.stdout


def probe(path):
    """The first video stream's codec, pixel format, size, frame rate and decoded frame count."""
    out = run([FFPROBE, "-v", "error", "-select_streams", "v:0", "-count_frames", "-show_entries",
               "stream=codec_name,pix_fmt,width,height,r_frame_rate,nb_read_frames", "-of", "json", path])
    return json.loads(out)["streams"][0]


class VideoTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = os.path.join(ARGS.tmp, f"plot_video_{os.getpid()}")
        shutil.rmtree(cls.work, ignore_errors=True)
        os.makedirs(cls.work)
        cls.data = os.path.join(cls.work, "data.h5")
        cls.rollout = os.path.join(cls.work, "full_space.h5")
        run([ARGS.cli, "-q", "simulate", os.path.join(REPO, "experiments", "scenes", "cloth.toml"), "--variant",
             "small", "-o", cls.data, "--max-frames", str(FRAMES)])
        run([ARGS.cli, "-q", "rollout", cls.data, "--method", "full_space", "--sequences", "all", "-o",
             cls.rollout])
        # A second "method" that blows up at frame 12: positions far away, then non-finite.
        cls.diverged = os.path.join(cls.work, "diverged.h5")
        shutil.copy(cls.rollout, cls.diverged)
        with h5py.File(cls.diverged, "r+") as f:
            g = f["rollouts/0"]
            g.attrs["method"] = np.bytes_("diverged")
            g.attrs["stable_horizon"] = 12
            g["positions"][12:16] *= 1e6
            g["positions"][16:] = np.nan

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    def make(self, name, *extra):
        out = os.path.join(self.work, name)
        written = run(["/usr/bin/python3", VIDEO, self.data, self.rollout, self.diverged, "-o", out, *extra])
        self.assertEqual(written.strip(), out)
        self.assertEqual([f for f in os.listdir(self.work) if ".tmp-" in f], [])
        return probe(out)

    def check_stream(self, s):
        self.assertEqual(s["codec_name"], "h264")
        self.assertEqual(s["pix_fmt"], "yuv420p")
        self.assertEqual(s["r_frame_rate"], "30/1")
        self.assertLessEqual(int(s["width"]), 1280)
        self.assertGreaterEqual(int(s["width"]), 320)
        self.assertLessEqual(int(s["height"]), 720)
        self.assertEqual(int(s["width"]) % 2, 0)
        self.assertEqual(int(s["height"]) % 2, 0)

    def test_every_frame(self):
        s = self.make("all.mp4")
        self.check_stream(s)
        self.assertEqual(int(s["nb_read_frames"]), FRAMES)
        print(f"all.mp4: {s['nb_read_frames']} frames, {s['width']}x{s['height']}, {s['codec_name']}")

    def test_subsampled_to_max_frames(self):
        s = self.make("short.mp4", "--max-frames", "7")  # stride ceil(20 / 7) = 3: frames 0, 3, ..., 18
        self.check_stream(s)
        self.assertEqual(int(s["nb_read_frames"]), 7)

    def test_fixed_and_tracking_camera(self):
        a = self.make("fixed.mp4", "--camera", "fixed", "--max-frames", "4")
        b = self.make("track.mp4", "--camera", "track", "--max-frames", "4")
        self.check_stream(a)
        self.check_stream(b)
        self.assertEqual(int(a["nb_read_frames"]), 4)

    def test_bad_input_exits_1_and_leaves_nothing(self):
        out = os.path.join(self.work, "bad.mp4")
        p = subprocess.run(["/usr/bin/python3", VIDEO, self.rollout, "-o", out], capture_output=True, text=True)
        self.assertEqual(p.returncode, 1)
        self.assertIn("plot_video.py: error:", p.stderr)
        self.assertFalse(os.path.exists(out))


def main():
    global ARGS
    ARGS, rest = script_test.arguments()
    return script_test.run(rest)


if __name__ == "__main__":
    sys.exit(main())
