#!/usr/bin/python3
"""The size check (docs/STYLE.md "Shape"): fails when a source of core/, datasets/, reference/, strategies/, harness/,
api/ or python/ is over MAX_FILE_LINES lines, or a function there is over MAX_FUNCTION_LINES: a file or function that
does several jobs is split by job. Functions are found by universal-ctags (its end: field), which scripts/setup.sh
installs; the check fails when ctags lists a function whose extent it cannot read (every one is measured), or finds
fewer than MIN_FUNCTIONS (a ctags that is not universal-ctags).

Usage: check_sizes.py SOURCE_DIR CTAGS            the check
       check_sizes.py --planted SOURCE_DIR CTAGS  the check of the check: a copy of the sources with a function of
                                                  MAX_FUNCTION_LINES + 1 lines planted in harness/table.cpp must fail,
                                                  naming it"""

import os
import re
import shutil
import subprocess
import sys
import tempfile

MAX_FILE_LINES = 600
MAX_FUNCTION_LINES = 100
MIN_FUNCTIONS = 1000
FOLDERS = ("core", "datasets", "reference", "strategies", "harness", "api", "python")
SUFFIXES = (".cpp", ".hpp", ".h", ".c", ".cl")
# Functions that are tables of cases, one entry a few lines, exempt by name: splitting them would only scatter a list.
EXEMPT = {("datasets/extremes_suite.cpp", "base_cases")}
TAG = re.compile(r"^([^\t]+)\t([^\t]+)\t.*\tline:(\d+)\b.*\tend:(\d+)\b")


def sources(root):
    found = []
    for folder in FOLDERS:
        for directory, _, files in os.walk(os.path.join(root, folder)):
            found += [os.path.relpath(os.path.join(directory, f), root) for f in files if f.endswith(SUFFIXES)]
    return sorted(found)


def check(root, ctags):
    problems = []
    files = sources(root)
    for source in files:
        with open(os.path.join(root, source), encoding="utf-8", errors="replace") as f:
            count = sum(1 for _ in f)
        if count > MAX_FILE_LINES:
            problems.append(f"  {source}: {count} lines (at most {MAX_FILE_LINES})")
    listed = subprocess.run([ctags, "--fields=+ne", "--c++-kinds=f", "--language-force=C++", "-o", "-"] + files, cwd=root, capture_output=True,
                            text=True, check=True).stdout.splitlines()
    measured = 0
    for line in listed:
        match = TAG.match(line)
        if not match:
            problems.append(f"  ctags lists a function whose extent cannot be read: {line[:200]}")
            continue
        name, file, first, last = match.group(1), match.group(2), int(match.group(3)), int(match.group(4))
        measured += 1
        length = last - first + 1
        if length > MAX_FUNCTION_LINES and (file, name) not in EXEMPT:
            problems.append(f"  {file}:{first}: {name}: {length} lines (at most {MAX_FUNCTION_LINES})")
    if len(files) < 100 or measured < MIN_FUNCTIONS:
        problems.append(f"  only {len(files)} sources and {measured} functions found under {root} (is {ctags} universal-ctags?)")
    if problems:
        print("sizes: split by job:\n" + "\n".join(problems))
        return 1
    print(f"sizes: {len(files)} sources within {MAX_FILE_LINES} lines, {measured} functions (every one ctags lists) within {MAX_FUNCTION_LINES}")
    return 0


def planted(root, ctags):
    with tempfile.TemporaryDirectory(prefix="sizes-") as copy:
        for folder in FOLDERS:
            shutil.copytree(os.path.join(root, folder), os.path.join(copy, folder))
        body = "\n".join(f"  total += {k};" for k in range(MAX_FUNCTION_LINES - 2))
        with open(os.path.join(copy, "harness", "table.cpp"), "a", encoding="utf-8") as f:
            f.write(f"\nnamespace {{\nint planted_long_function(int total) {{\n{body}\n  return total;\n}}\n}}  // namespace\n")
        result = subprocess.run([sys.executable, __file__, copy, ctags], capture_output=True, text=True)
    if result.returncode != 0 and f"planted_long_function: {MAX_FUNCTION_LINES + 1} lines" in result.stdout:
        print("sizes: a planted function of", MAX_FUNCTION_LINES + 1, "lines fails the check, as it must")
        return 0
    print("sizes: the check passed a planted function of", MAX_FUNCTION_LINES + 1, "lines:\n" + result.stdout + result.stderr)
    return 1


if __name__ == "__main__":
    if sys.argv[1] == "--planted":
        sys.exit(planted(os.path.abspath(sys.argv[2]), sys.argv[3]))
    sys.exit(check(os.path.abspath(sys.argv[1]), sys.argv[2]))
