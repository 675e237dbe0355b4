#!/usr/bin/python3
"""Runs the command blocks of the README and of every page under docs/, as a reader would, and checks the output each
page claims (docs/development.md, "The docs walkthrough").

Each page runs in one bash of its own, from the repository's root, with a fresh HOME, stopping at the first failing
command (set -euo pipefail). A ```sh block runs unless the line before it is
    <!-- docs-walkthrough: skip: REASON -->           (printed with its reason), or
    <!-- docs-walkthrough: needs data -->             (run only where the public data is found; else the rest of the
                                                       page is skipped, saying so).
The first ```text block after a ```sh block (before the next one) is the output that block claims: each of its lines must appear, in order,
among the lines the block printed (stdout and stderr), every number and long hex digest masked and runs of blanks
taken as one; a `…` inside a line matches anything, and a line `...` is ignored (lines between are skipped anyway).

Usage: scripts/docs-walkthrough.py [PAGE.md ...]   (default: README.md and docs/*.md); after scripts/build.sh.
Exit status: 0 when every page ran and printed what it claims, 1 otherwise."""

import os
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DIRECTIVE = re.compile(r"<!--\s*docs-walkthrough:\s*(skip:\s*(?P<reason>.*?)|(?P<data>needs data))\s*-->")
MARKER = "@@docs-walkthrough block {}@@"


def blocks_of(page):
    """[(index, code, directive, reason, claimed lines or None)] for every ```sh block of a page, in order."""
    lines = open(page, encoding="utf-8").read().split("\n")
    found = []
    i = 0
    while i < len(lines):
        if lines[i].strip() != "```sh":
            i += 1
            continue
        previous = lines[i - 1].strip() if i > 0 else ""
        match = DIRECTIVE.fullmatch(previous)
        directive = None if not match else ("data" if match.group("data") else "skip")
        reason = match.group("reason") if match and match.group("reason") else ""
        end = lines.index("```", i + 1)
        code = "\n".join(lines[i + 1 : end])
        claimed = None
        after = end + 1
        while after < len(lines) and lines[after].strip() not in ("```text", "```sh"):
            after += 1
        if after < len(lines) and lines[after].strip() == "```text":
            close = lines.index("```", after + 1)
            claimed = lines[after + 1 : close]
            end = close
        found.append((len(found), code, directive, reason, claimed))
        i = end + 1
    return found


def masked(line):
    """A line with its digests and numbers masked and its blanks collapsed: what stays the same from run to run."""
    line = re.sub(r"\b[0-9a-f]{16,}\b", "#", line)
    line = re.sub(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?", "#", line)
    return " ".join(line.split())


def claimed_found(claimed, printed):
    """The first claimed line not found, in order, among the printed ones (None: all found)."""
    actual = [masked(line) for line in printed]
    at = 0
    for line in claimed:
        if line.strip() in ("", "..."):
            continue
        pattern = re.compile(".*".join(re.escape(part) for part in masked(line).split("…")))
        while at < len(actual) and not pattern.fullmatch(actual[at]):
            at += 1
        if at == len(actual):
            return line
        at += 1
    return None


def data_dir():
    if os.environ.get("CCDBENCH_DATA_DIR"):
        return os.environ["CCDBENCH_DATA_DIR"]
    found = subprocess.run(["bash", "-c", "source scripts/data-dir.sh >/dev/null 2>&1; echo ${CCDBENCH_DATA_DIR:-}"], cwd=ROOT, capture_output=True,
                           text=True).stdout.strip()
    return found or None


def run_page(page, data):
    """Runs a page's blocks; returns (ran, skipped, failure or None), printing as it goes."""
    name = os.path.relpath(page, ROOT)
    blocks = blocks_of(page)
    if not blocks:
        return 0, 0, None
    script = ["set -euo pipefail"]
    to_run = []
    skipped = 0
    for index, code, directive, reason, claimed in blocks:
        if directive == "skip":
            print(f"docs-walkthrough: {name}: block {index + 1} skipped: {reason}")
            skipped += 1
            continue
        if directive == "data" and not data:
            print(f"docs-walkthrough: {name}: block {index + 1} and the rest of the page skipped: they need the public data (docs/DATA.md)")
            skipped += len(blocks) - index
            break
        script.append(f"printf '\\n%s\\n' '{MARKER.format(index)}'")
        script.append(code)
        to_run.append((index, claimed))
    script.append(f"printf '\\n%s\\n' '{MARKER.format('end')}'")
    with tempfile.TemporaryDirectory(prefix="docs-walkthrough-") as home:
        env = dict(os.environ, HOME=home)
        if data:
            env["CCDBENCH_DATA_DIR"] = data
        start = time.monotonic()
        result = subprocess.run(["bash", "-c", "\n".join(script)], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        seconds = time.monotonic() - start
    output = result.stdout.split("\n")
    # Each block's printed lines: between its marker and the next.
    starts = {line: k for k, line in enumerate(output) if line.startswith("@@docs-walkthrough block ")}
    if result.returncode != 0:
        ran_until = max((k for k in starts.values()), default=0)
        tail = "\n".join(output[ran_until:][-40:])
        return len(to_run), skipped, f"a command failed (exit status {result.returncode}); the output of the block it was in ends:\n{tail}"
    for index, claimed in to_run:
        first = starts.get(MARKER.format(index))
        later = sorted(k for k in starts.values() if first is not None and k > first)
        printed = output[first + 1 : later[0]] if first is not None and later else []
        if claimed is not None:
            missing = claimed_found(claimed, printed)
            if missing is not None:
                shown = "\n".join(printed[-30:])
                return len(to_run), skipped, f"block {index + 1} did not print, in order, what the page claims; first line not found:\n  {missing}\nit printed (last lines):\n{shown}"
    print(f"docs-walkthrough: {name}: {len(to_run)} block(s) ran as shown in {seconds:.0f} s" + (f", {skipped} skipped" if skipped else ""))
    return len(to_run), skipped, None


def main(arguments):
    pages = [os.path.abspath(p) for p in arguments] or [os.path.join(ROOT, "README.md")] + sorted(
        os.path.join(ROOT, "docs", f) for f in os.listdir(os.path.join(ROOT, "docs")) if f.endswith(".md"))
    data = data_dir()
    failed = 0
    total = 0
    for page in pages:
        ran, _, failure = run_page(page, data)
        total += ran
        if failure:
            failed += 1
            print(f"docs-walkthrough: {os.path.relpath(page, ROOT)}: FAILED: {failure}", file=sys.stderr)
    print(f"docs-walkthrough: {total} block(s) on {len(pages)} page(s); " + ("every one ran as shown" if not failed else f"{failed} page(s) FAILED"))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
