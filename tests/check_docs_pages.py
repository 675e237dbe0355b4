#!/usr/bin/python3
"""The docs check (docs/development.md, "The docs walkthrough"): the README and the pages under docs/ hold together.
Fails, listing every problem, when
  - a relative link of a page names a file that does not exist, or an anchor (#...) that is no heading of its page;
  - a page cites docs/DESIGN.md's section §N that does not exist;
  - a source cites a page's section, `docs/PAGE.md "Heading"`, that is no heading of that page;
  - a page under docs/ cannot be reached from the README within two links;
  - a page passes kMaxLines lines.
Usage: check_docs_pages.py SOURCE_DIR"""

import os
import re
import sys

MAX_LINES = 400
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
SECTION = re.compile(r"§(\d+)")
CITED_PAGE = re.compile(r"docs/([a-z][a-z-]*)\.md \"([^\"]+)\"")
SOURCES = (".cpp", ".hpp", ".h", ".c", ".sh", ".py", ".cmake", ".txt", ".yml")


def slug(heading):
    """GitHub's anchor of a heading: lower case, punctuation but '-' and '_' dropped, spaces made '-'."""
    text = re.sub(r"`", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def headings(path):
    found = set()
    fenced = False
    for line in open(path, encoding="utf-8"):
        if line.startswith("```"):
            fenced = not fenced
        elif not fenced and line.startswith("#"):
            found.add(line.lstrip("#").strip())
    return found


def main(root):
    pages = [os.path.join(root, "README.md")] + sorted(
        os.path.join(root, "docs", f) for f in os.listdir(os.path.join(root, "docs")) if f.endswith(".md"))
    design = open(os.path.join(root, "docs/DESIGN.md"), encoding="utf-8").read()
    problems = []
    links = {}
    for page in pages:
        name = os.path.relpath(page, root)
        text = open(page, encoding="utf-8").read()
        lines = text.count("\n")
        if lines > MAX_LINES:
            problems.append(f"{name}: {lines} lines (at most {MAX_LINES}): split it by task")
        prose = re.sub(r"```.*?```", "", text, flags=re.S)
        links[page] = set()
        for target in LINK.findall(prose):
            if re.match(r"[a-z]+:", target):
                continue  # https:, mailto:
            file, _, anchor = target.partition("#")
            resolved = os.path.normpath(os.path.join(os.path.dirname(page), file)) if file else page
            if not os.path.exists(resolved):
                problems.append(f"{name}: links to {target}, which does not exist")
                continue
            links[page].add(resolved)
            if anchor and resolved.endswith(".md") and anchor not in {slug(h) for h in headings(resolved)}:
                problems.append(f"{name}: links to {target}: {os.path.relpath(resolved, root)} has no heading with that anchor")
        for number in SECTION.findall(prose):
            if f"\n## {number}. " not in design:
                problems.append(f"{name}: cites §{number}, which docs/DESIGN.md does not have")
    readme = pages[0]
    reached = {readme} | links[readme]
    for page in list(links[readme]):
        reached |= links.get(page, set())
    for page in pages[1:]:
        if page not in reached:
            problems.append(f"{os.path.relpath(page, root)}: not reachable from the README within two links")
    for folder, _, files in os.walk(root):
        if any(part in folder for part in ("/build", "/.git", "/data/", "/reports")):
            continue
        for file in files:
            if not file.endswith(SOURCES) and file != "CMakeLists.txt":
                continue
            path = os.path.join(folder, file)
            try:
                text = open(path, encoding="utf-8").read()
            except (UnicodeDecodeError, OSError):
                continue
            for page, heading in CITED_PAGE.findall(text):
                target = os.path.join(root, "docs", page + ".md")
                if page in ("DESIGN", "STYLE"):
                    continue  # tests/check_docs.cmake holds those
                if not os.path.exists(target):
                    problems.append(f"{os.path.relpath(path, root)}: cites docs/{page}.md, which does not exist")
                elif heading not in headings(target):
                    problems.append(f"{os.path.relpath(path, root)}: cites docs/{page}.md \"{heading}\", which is no heading of that page")
    for problem in problems:
        print(problem)
    print(f"docs: {len(pages)} pages, {sum(len(v) for v in links.values())} links checked; " + (f"{len(problems)} problem(s)" if problems else "all hold"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else ".")))
