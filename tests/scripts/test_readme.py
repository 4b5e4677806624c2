#!/usr/bin/python3
"""README.md stays a guide that matches the binary: it is under 30,000 bytes; every
`latentbench <subcommand>` it shows in code exists in `latentbench --help`; every long option
that `latentbench --help` and `latentbench <subcommand> --help` print appears in it, as do the
options of the user-facing scripts and every `scripts/run` command; it names no issue numbers;
and the repository files it names in code exist. Run by ctest (label unit):

  /usr/bin/python3 tests/scripts/test_readme.py --cli build/latentbench --tmp build/tests/tmp
"""
import pathlib
import re
import subprocess
import sys
import unittest

import script_test

REPO = pathlib.Path(__file__).resolve().parent.parent.parent
README = REPO / "README.md"
MAX_BYTES = 30_000
ARGS = None
SCRIPTS = ("scripts/run_local.py", "scripts/plot_video.py", "scripts/export_rollout.py")

# A long option as CLI11 prints it (`--max-frames`, `-o,--output`), not followed by more name.
LONG_OPTION = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*(?![\w-])")
# "issue 40", "issues 14 and 15", "Issue #7", "#40".
ISSUE_NUMBER = re.compile(r"\bissues?\s*#?\d+|(?<![\w&/#])#\d+\b", re.IGNORECASE)


def run(argv):
    p = subprocess.run([str(a) for a in argv], capture_output=True, text=True, cwd=REPO)
    if p.returncode != 0:
        raise AssertionError(f"{' '.join(map(str, argv))} exited {p.returncode}:\n{p.stdout}\n{p.stderr}")
    return p.stdout


def subcommands(top_help):
    """Names listed under "Subcommands:" in CLI11's help."""
    names, inside = [], False
    for line in top_help.splitlines():
        if line.strip() == "Subcommands:":
            inside = True
            continue
        if inside:
            m = re.match(r"^\s{2}([a-z][a-z0-9-]*)\b", line)
            if m:
                names.append(m.group(1))
            elif line.strip() and not line.startswith(" "):
                inside = False
    return names


def code_text(markdown):
    """Every fenced code block and every inline code span, one string per piece."""
    pieces = []
    fence = re.compile(r"^```[^\n]*\n(.*?)^```", re.S | re.M)
    for m in fence.finditer(markdown):
        pieces.append(m.group(1))
    prose = fence.sub("", markdown)
    # A span may continue on the next line (Markdown reads the line break as a space), not
    # across a blank line.
    spans = re.findall(r"``((?:[^`]|`(?!`))+?)``|`((?:[^`\n]|\n(?!\n))+)`", prose)
    pieces += [" ".join((a or b).split()) for a, b in spans]
    return pieces


def shown_subcommands(markdown):
    """(subcommand, context) for every `latentbench SUB` in code, after global options."""
    found = []
    pattern = re.compile(r"(?:^|(?<=[\s/`(]))latentbench((?:\s+(?:\[[^\]]*\]|-[a-zA-Z-]+(?:\s+\d+)?))*)"
                         r"\s+([A-Za-z][A-Za-z0-9-]*)")
    for piece in code_text(markdown):
        for m in pattern.finditer(piece):
            name = m.group(2)
            if name.isupper():  # a placeholder such as SUBCOMMAND
                continue
            found.append((name, m.group(0)))
    return found


class Readme(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.text = README.read_text(encoding="utf-8")
        cls.top_help = run([ARGS.cli, "--help"])
        cls.subs = subcommands(cls.top_help)
        cls.sub_help = {s: run([ARGS.cli, s, "--help"]) for s in cls.subs}

    def test_help_lists_subcommands(self):
        # Guards the parser of the help text, so the other tests cannot pass vacuously.
        for name in ("run", "simulate", "train-ae", "fit", "rollout"):
            self.assertIn(name, self.subs, self.top_help)

    def test_under_30000_bytes(self):
        size = len(README.read_bytes())
        self.assertLess(size, MAX_BYTES, f"README.md is {size} bytes; the guide must stay under "
                        f"{MAX_BYTES} (move detail to the code's own comments or paper/)")

    def test_every_shown_subcommand_exists(self):
        shown = shown_subcommands(self.text)
        self.assertGreater(len(shown), 10, "found almost no `latentbench <subcommand>` in README")
        unknown = sorted({f"{name!r} in {context.strip()!r}" for name, context in shown
                          if name not in self.subs})
        self.assertEqual(unknown, [], "README shows subcommands that `latentbench --help` does "
                         f"not list ({', '.join(self.subs)})")

    def test_every_long_option_is_documented(self):
        documented = set(LONG_OPTION.findall(self.text))
        missing = []
        for source, text in [("latentbench", self.top_help)] + [
                (f"latentbench {s}", h) for s, h in self.sub_help.items()]:
            for option in sorted(set(LONG_OPTION.findall(text))):
                if option != "--help" and option not in documented:
                    missing.append(f"{source} {option}")
        self.assertEqual(missing, [], "options printed by --help but absent from README.md")

    def test_every_script_option_is_documented(self):
        # The user-facing scripts' argparse options, read from their source (running them
        # would need matplotlib, meshio or ffmpeg), and the commands of scripts/run.
        documented = set(LONG_OPTION.findall(self.text))
        missing = []
        for script in SCRIPTS:
            source = (REPO / script).read_text(encoding="utf-8")
            options = re.findall(r"add_argument\((?:\s*\"-\w\",)?\s*\"(--[a-z][a-z0-9-]*)\"", source)
            self.assertTrue(options, f"no argparse options found in {script}")
            missing += [f"{script} {o}" for o in sorted(set(options)) if o not in documented]
        run_script = (REPO / "scripts" / "run").read_text(encoding="utf-8")
        commands = re.findall(r"^  ([a-z][a-z-]*)\)", run_script, re.M)
        self.assertIn("quickstart", commands)
        missing += [f"scripts/run {c}" for c in commands
                    if not re.search(rf"scripts/run {re.escape(c)}(?![\w-])", self.text)]
        self.assertEqual(missing, [], "script options or commands absent from README.md")

    def test_links_within_the_readme_resolve(self):
        prose = re.sub(r"^```.*?^```", "", self.text, flags=re.S | re.M)
        anchors = set()
        for heading in re.findall(r"^#{1,6} (.+)$", prose, re.M):
            # GitHub's anchors: lower case, punctuation dropped, spaces to hyphens.
            anchors.add(re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-"))
        broken = sorted(set(re.findall(r"\]\(#([^)]+)\)", prose)) - anchors)
        self.assertEqual(broken, [], f"links to headings that do not exist ({sorted(anchors)})")

    def test_no_issue_numbers(self):
        hits = [f"line {self.text.count(chr(10), 0, m.start()) + 1}: {m.group(0)!r}"
                for m in ISSUE_NUMBER.finditer(self.text)]
        self.assertEqual(hits, [], "README names issue numbers")

    def test_named_repository_files_exist(self):
        # Paths in code spans under the repository's own folders, placeholders excepted.
        roots = ("scripts/", "experiments/", "src/", "tests/", "baselines/", "paper/", "results/")
        missing = set()
        for piece in code_text(self.text):
            for token in re.findall(r"[^\s`'\"(),;:\[\]|=]+", piece):
                token = token.rstrip(".")
                if not token.startswith(roots) or any(c in token for c in "<*{$"):
                    continue
                if any(re.fullmatch(r"[A-Z][A-Z_]*", part) for part in token.split("/")):
                    continue  # a placeholder such as results/NAME/
                if not (REPO / token).exists():
                    missing.add(token)
        # Outputs of commands, not files in the repository.
        missing -= {"results/bench/DATE-COMMIT.json"}
        self.assertEqual(sorted(missing), [], "README names files that do not exist")


def main():
    global ARGS
    ARGS, rest = script_test.arguments()
    return script_test.run(rest)


if __name__ == "__main__":
    sys.exit(main())
