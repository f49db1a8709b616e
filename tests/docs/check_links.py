#!/usr/bin/python3
"""Every relative link and image in the project's Markdown resolves (issue 30): README.md, docs/, bench/README.md,
formats/SCHEMA.md and the examples' READMEs. A link to a file must name one that exists; a link with #anchor into a
Markdown file must name one of its headings (GitHub's anchors: lower case, punctuation dropped, spaces as hyphens).
External links (http, https, mailto) are not followed. Prints each broken link as FILE:LINE: TARGET and exits 1.

    check_links.py REPO_ROOT
"""
import re
import sys
from pathlib import Path

LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
FENCE = re.compile(r"^\s*(```|~~~)")


def anchors(markdown):
    """GitHub's anchors of a Markdown file's headings (outside code fences), with -1, -2 for repeats."""
    seen, result, fenced = {}, set(), False
    for line in markdown.read_text(encoding="utf-8").splitlines():
        if FENCE.match(line):
            fenced = not fenced
            continue
        heading = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if fenced or not heading:
            continue
        text = re.sub(r"`|\*\*|__|\[|\]\([^)]*\)", "", heading.group(1)).strip().lower()
        slug = re.sub(r"[^\w\- ]", "", text).replace(" ", "-")
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        result.add(slug if count == 0 else f"{slug}-{count}")
    return result


def links(markdown):
    """(line number, target) of every inline link and image outside code fences and code spans."""
    fenced = False
    for number, line in enumerate(markdown.read_text(encoding="utf-8").splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if fenced:
            continue
        for match in LINK.finditer(re.sub(r"`[^`]*`", "", line)):
            yield number, match.group(1)


def main():
    root = Path(sys.argv[1]).resolve()
    files = [root / "README.md", root / "bench" / "README.md", root / "formats" / "SCHEMA.md"]
    files += sorted((root / "docs").glob("*.md")) + sorted((root / "examples").glob("*/README.md"))
    broken, checked = [], 0
    for markdown in files:
        if not markdown.exists():
            broken.append(f"{markdown.relative_to(root)}: missing")
            continue
        for number, target in links(markdown):
            if re.match(r"^[a-z]+:", target):  # http:, https:, mailto:
                continue
            checked += 1
            path, _, anchor = target.partition("#")
            resolved = (markdown.parent / path).resolve() if path else markdown
            where = f"{markdown.relative_to(root)}:{number}: {target}"
            if not resolved.exists():
                broken.append(where + " (no such file)")
            elif anchor and resolved.suffix == ".md" and anchor not in anchors(resolved):
                broken.append(where + f" (no heading #{anchor} in {resolved.relative_to(root)})")
    for line in broken:
        print(line)
    print(f"{checked} relative links in {len(files)} files, {len(broken)} broken")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
