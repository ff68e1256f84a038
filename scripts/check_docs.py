#!/usr/bin/env python3
"""Checks the documentation for rot; prints one line per problem and exits 1 if there is any.

  check_docs.py [--repo DIR] [links] [mentions] [examples]     (no check named: all three)

links     every relative link and image in README.md, CHANGELOG.md and docs/**/*.md points to a
          file or folder that exists, and its #anchor (if any) to a heading of that page.
mentions  every path docs/....{md,png,json,csv} named in a source, script, test, interface,
          launch, scene or docs file exists (generators and comments name their pages this way).
examples  README.md holds each examples/*.cpp between its BEGIN/END README EXAMPLE markers
          verbatim (test/unit/test_docs.cpp also compiles and runs the program).

Run by test/unit/test_docs.cpp in the default suite (scripts/test).
"""
import argparse
import os
import re
import sys

# Pages the docs index links that other branches of the same work (issues 29-31) add; until they
# are merged they may be missing here, and each missing one is printed as a note, not an error.
# Delete an entry once its page is on main.
PAGES_FROM_OPEN_BRANCHES = set()

# Where `mentions` looks: the package's own text files (not the build workspaces).
MENTION_ROOTS = ["README.md", "CHANGELOG.md", "CMakeLists.txt", "package.xml", "action", "cmake",
                 "docs", "examples", "include", "launch", "msg", "rviz", "scenes", "scripts",
                 "src", "srv", "studies", "test"]
TEXT_SUFFIXES = (".md", ".cpp", ".hpp", ".h", ".py", ".txt", ".cmake", ".msg", ".srv",
                 ".action", ".launch", ".test", ".yaml", ".xml", ".supp", ".rviz", ".sh", "")

LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(([^()\s]+)(?:\s+\"[^\"]*\")?\)")
MENTION = re.compile(r"\bdocs/[\w./-]*?\.(?:md|png|json|csv)\b")
FENCE = re.compile(r"^\s*(```|~~~)")
INLINE_CODE = re.compile(r"`[^`]*`")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
MARKER_BEGIN = "// BEGIN README EXAMPLE"
MARKER_END = "// END README EXAMPLE"


def markdown_pages(repo):
    pages = [p for p in ("README.md", "CHANGELOG.md") if os.path.isfile(os.path.join(repo, p))]
    for root, dirs, files in os.walk(os.path.join(repo, "docs")):
        dirs.sort()
        for name in sorted(files):
            if name.endswith(".md"):
                pages.append(os.path.relpath(os.path.join(root, name), repo))
    return pages


def prose_lines(text, keep_code=False):
    """(line number, line) outside fenced code blocks, inline code removed unless keep_code."""
    fenced = False
    for number, line in enumerate(text.splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            yield number, line if keep_code else INLINE_CODE.sub("", line)


def github_slug(heading):
    """The anchor GitHub gives a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link in a heading: its text
    text = text.strip().lower().replace("`", "")
    text = "".join(c for c in text if c.isalnum() or c in " -_")
    return text.replace(" ", "-")


def anchors_of(path, cache={}):
    if path not in cache:
        slugs, seen = set(), {}
        with open(path, encoding="utf-8") as f:
            for _, line in prose_lines(f.read(), keep_code=True):
                m = HEADING.match(line)
                if m:
                    slug = github_slug(m.group(2))
                    n = seen.get(slug, 0)
                    seen[slug] = n + 1
                    slugs.add(slug if n == 0 else "%s-%d" % (slug, n))
        cache[path] = slugs
    return cache[path]


def missing_page_note(rel, where, notes):
    if rel in PAGES_FROM_OPEN_BRANCHES:
        notes.append("note: %s: %s is not in this tree yet (added by another open branch)" %
                     (where, rel))
        return True
    return False


def check_links(repo, problems, notes):
    for page in markdown_pages(repo):
        page_dir = os.path.dirname(page)
        with open(os.path.join(repo, page), encoding="utf-8") as f:
            text = f.read()
        for number, line in prose_lines(text):
            for m in LINK.finditer(line):
                target = m.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
                    continue
                path, _, anchor = target.partition("#")
                where = "%s:%d" % (page, number)
                rel = os.path.normpath(os.path.join(page_dir, path)) if path else page
                full = os.path.join(repo, rel)
                if path and not os.path.exists(full):
                    if not missing_page_note(rel, where, notes):
                        problems.append("%s: broken link %s (no %s)" % (where, target, rel))
                    continue
                if anchor and rel.endswith(".md") and anchor not in anchors_of(full):
                    problems.append("%s: broken link %s (no heading #%s in %s)" %
                                    (where, target, anchor, rel))


def mention_files(repo):
    for top in MENTION_ROOTS:
        full = os.path.join(repo, top)
        if os.path.isfile(full):
            yield top
        for root, dirs, files in os.walk(full):
            dirs[:] = sorted(d for d in dirs if not d.startswith("."))
            for name in sorted(files):
                if os.path.splitext(name)[1] in TEXT_SUFFIXES:
                    yield os.path.relpath(os.path.join(root, name), repo)


def check_mentions(repo, problems, notes):
    for rel in mention_files(repo):
        if rel == os.path.join("scripts", "check_docs.py"):
            continue  # names the pages of PAGES_FROM_OPEN_BRANCHES itself
        try:
            with open(os.path.join(repo, rel), encoding="utf-8") as f:
                lines = f.read().splitlines()
        except (UnicodeDecodeError, OSError):
            continue  # binary data (fuzz corpus, images)
        for number, line in enumerate(lines, 1):
            for m in MENTION.finditer(line):
                path = m.group(0).rstrip(".")
                where = "%s:%d" % (rel, number)
                if not os.path.exists(os.path.join(repo, path)) and \
                        not missing_page_note(path, where, notes):
                    problems.append("%s: names %s, which does not exist" % (where, path))


def check_examples(repo, problems, notes):
    with open(os.path.join(repo, "README.md"), encoding="utf-8") as f:
        readme = f.read()
    folder = os.path.join(repo, "examples")
    for name in sorted(os.listdir(folder)) if os.path.isdir(folder) else []:
        if not name.endswith(".cpp"):
            continue
        with open(os.path.join(folder, name), encoding="utf-8") as f:
            source = f.read()
        begin, end = source.find(MARKER_BEGIN), source.find(MARKER_END)
        if begin < 0 or end < begin:
            problems.append("examples/%s: no %s ... %s block" % (name, MARKER_BEGIN, MARKER_END))
            continue
        snippet = source[source.index("\n", begin) + 1:end]
        if snippet not in readme:
            problems.append("README.md: does not hold examples/%s (between its markers) verbatim"
                            % name)


def main():
    checks = {"links": check_links, "mentions": check_mentions, "examples": check_examples}
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repo", default=os.path.join(os.path.dirname(__file__), ".."))
    ap.add_argument("check", nargs="*", choices=sorted(checks) + [[]])
    args = ap.parse_args()
    problems, notes = [], []
    for name in args.check or sorted(checks):
        checks[name](os.path.abspath(args.repo), problems, notes)
    for line in notes + problems:
        print(line)
    print("%d problem(s)" % len(problems))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
