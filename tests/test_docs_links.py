"""Every link and image in README.md and docs/*.md resolves: the file it names exists,
and so does the heading an #anchor names (GitHub's slug of it)."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path
from urllib.parse import unquote

ROOT = Path(__file__).resolve().parent.parent
FENCE = re.compile(r"^(```|~~~).*?^\1[^\n]*$", re.M | re.S)
INDENTED = re.compile(r"(?:(?<=\n\n)|^)(?:(?: {4}|\t)[^\n]*\n?)+", re.M)
CODE = re.compile(r"(`+)(?!`).+?(?<!`)\1(?!`)", re.S)
LINK = re.compile(r"(!?)\[((?:[^\[\]]|\[[^\[\]]*\])*)\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")


def slug(heading: str) -> str:
    text = re.sub(r"`([^`]*)`", r"\1", heading.strip()).lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    seen: dict[str, int] = {}
    out = set()
    for line in FENCE.sub("", path.read_text(encoding="utf-8")).splitlines():
        match = re.match(r"#{1,6} (.*)", line)
        if match:
            base = slug(match.group(1))
            n = seen.get(base, 0)
            seen[base] = n + 1
            out.add(base if n == 0 else f"{base}-{n}")
    return out


def links(path: Path) -> Iterator[tuple[int, str, str]]:
    text = path.read_text(encoding="utf-8")
    text = FENCE.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    text = INDENTED.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    text = CODE.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    for match in LINK.finditer(text):
        line = text.count("\n", 0, match.start()) + 1
        yield line, ("image" if match.group(1) else "link"), match.group(3)


def test_every_link_in_the_readme_and_the_docs_resolves() -> None:
    files = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    broken, checked = [], 0
    for source in files:
        for line, kind, target in links(source):
            if re.match(r"[a-z][a-z0-9+.-]*:", target):  # http:, mailto:: not checked here
                continue
            checked += 1
            name, _, anchor = target.partition("#")
            file = (source.parent / unquote(name)).resolve() if name else source
            if not file.exists():
                broken.append(f"{source.relative_to(ROOT)}:{line}: {kind} {target}: no such file")
            elif anchor and (file.suffix != ".md" or anchor not in anchors(file)):
                broken.append(f"{source.relative_to(ROOT)}:{line}: {kind} {target}: no heading")
    assert checked > 20
    assert broken == []


def test_the_readme_is_the_page_a_newcomer_reads() -> None:
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 400
    text = "\n".join(lines)
    for subject in (
        "console",
        "repl",
        "cli",
        "targets",
        "cells",
        "plant",
        "windows",
        "protocol",
        "performance",
        "reliability",
        "architecture",
    ):
        assert f"docs/{subject}.md" in text, subject
    assert "rac-console paths" in text
